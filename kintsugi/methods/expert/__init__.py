"""kintsugi.methods.expert."""

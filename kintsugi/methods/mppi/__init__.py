"""kintsugi.methods.mppi."""

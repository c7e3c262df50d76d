"""kintsugi.methods.recovery.method."""

"""kintsugi.core."""

namespace raster { int placeholder() { return 0; } }  // replaced by the raster module

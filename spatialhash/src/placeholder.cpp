namespace spatialhash { int placeholder() { return 0; } }  // replaced by the spatialhash module

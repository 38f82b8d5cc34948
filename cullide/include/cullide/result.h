// cullide/result.h: the error type of the cullide library.
//
// Every operation that can fail on caller data (a file, a mesh, an option) returns Result<T> or
// Status. The message names what is wrong and where ("file.obj:12: face index 9 is beyond the
// vertex list (size 8)"). A failed call changes nothing the caller can see.
//
// cullide sits on top of raster, so it uses raster's error type rather than a third copy of the
// same fifty lines (spatialhash keeps its own: it must not depend on raster). Interface: ok(),
// explicit operator bool, value() (asserts ok()), error().message.
#pragma once

#include "raster/result.h"

namespace cullide {

using Error = raster::Error;
template <class T>
using Result = raster::Result<T>;
using Status = raster::Status;

}  // namespace cullide

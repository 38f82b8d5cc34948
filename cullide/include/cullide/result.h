// cullide/result.h: the error type of the cullide library.
//
// Every operation that can fail on caller data (a file, a mesh, an option) returns Result<T> or
// Status. The message names what is wrong and where ("file.obj:12: face index 9 is beyond the
// vertex list (size 8)"). A failed call changes nothing the caller can see.
//
// The one error type of the project (outcome/result.h, through raster's names), so cullide::Error,
// raster::Error and spatialhash::Error are the same type. Interface: ok(), explicit operator bool,
// value() (asserts ok()), error().message.
#pragma once

#include "raster/result.h"

namespace cullide {

using Error = raster::Error;
template <class T>
using Result = raster::Result<T>;
using Status = raster::Status;

}  // namespace cullide

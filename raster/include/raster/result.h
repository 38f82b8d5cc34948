// raster/result.h: the error type of the raster library: outcome/result.h's, named in raster.
//
// Every call that can fail on caller data returns Result<T> or Status; the message names the
// element, its index and the limit ("draw 3: index 17 at position 5 is beyond the vertex list
// (size 12)"). A failed call changes nothing the caller can see.
#pragma once

#include "outcome/result.h"

namespace raster {

using outcome::Error;
using outcome::Result;
using outcome::Status;

}  // namespace raster

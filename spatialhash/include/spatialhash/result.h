// spatialhash/result.h: the error type of the spatialhash library: outcome/result.h's (a
// header-only target that links nothing: spatialhash does not depend on raster), named in
// spatialhash.
//
// Every entry point that can fail on caller data returns Result<T>; the message names the element
// and the limit ("box 17: lo[1] = nan is not finite"). A failed call has no effect the caller can see.
#pragma once

#include "outcome/result.h"

namespace spatialhash {

using outcome::Error;
using outcome::Result;

}  // namespace spatialhash

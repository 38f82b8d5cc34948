// emulator_device.h (private): lets cullide.cpp recognise the built-in emulator device, whose
// exact-bounds passes it may run through raster::VisibilityPass (identical answers, one
// rasterization per item instead of four; cullide/cullide.h).
#pragma once

#include "cullide/query_device.h"

namespace cullide::detail {

// The emulator device's worker count, or -1 when `device` is another device.
[[nodiscard]] int emulator_threads(const QueryDevice& device);

}  // namespace cullide::detail

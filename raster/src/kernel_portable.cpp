// kernel_portable.cpp: the coverage + depth kernel for any CPU (see raster_kernel.inc).
#include <algorithm>
#include <bit>
#include <cmath>

#include "pipeline.h"

namespace raster::detail {
namespace portable {
#include "raster_kernel.inc"
}  // namespace portable

std::uint64_t raster_rect_portable(const SetupTri& tri, DepthFormat format, DepthFunc func, bool write,
                                   std::uint32_t* depth, int stride, int rx0, int ry0, int rx1, int ry1,
                                   bool stop_at_first) {
    return portable::raster_rect_kernel(tri, format, func, write, depth, stride, rx0, ry0, rx1, ry1, stop_at_first);
}

}  // namespace raster::detail

// osmesa_query_device.h: a cullide::QueryDevice on real GL (Mesa llvmpipe through OSMesa), so the
// CULLIDE pipeline's very same pass sequence runs on the oracle. Tests and benchmarks only.
#pragma once

#include <memory>

#include "cullide/query_device.h"

namespace cullide_oracle {

// Fails when OSMesa cannot make a context (the message says why). The GL context is re-created
// when clear() asks for another size or format. RasterMode::ExactBounds draws are refused (a
// real GL has no such mode): execute() then fails naming the command.
[[nodiscard]] cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_osmesa_query_device();

}  // namespace cullide_oracle

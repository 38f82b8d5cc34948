// validate.h (private): checks a batch against a target before anything is drawn.
#pragma once

#include "raster/command_batch.h"

namespace raster::detail {
[[nodiscard]] Status validate(const DepthTarget& target, const CommandBatch& batch);
}  // namespace raster::detail

// validate.h (private): checks a batch against a target before anything is drawn.
#pragma once

#include "raster/command_batch.h"

#include <span>

namespace raster::detail {
[[nodiscard]] Status validate(const DepthTarget& target, const CommandBatch& batch);

// The batches of one sequence in order: the first failure's batch index and message (index =
// batches.size() when all pass; a null batch is the caller's check). The same answer as validate()
// on each batch in turn; vertex lists found wholly valid in one batch are not checked again in a
// later one (the lists cannot change during the call).
struct SequenceCheck {
    std::size_t batch;
    Status status;
};
[[nodiscard]] SequenceCheck validate_sequence(const DepthTarget& target, std::span<const CommandBatch* const> batches);
}  // namespace raster::detail

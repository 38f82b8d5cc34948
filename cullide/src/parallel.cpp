#include "parallel.h"

#include "raster/detail/parallel.h"

namespace cullide::detail {

int effective_threads(int threads) { return raster::detail::effective_threads(threads); }

void parallel_chunks(int threads, std::size_t chunks, const std::function<void(std::size_t)>& fn) {
    raster::detail::parallel_for(threads, chunks, fn);
}

}  // namespace cullide::detail

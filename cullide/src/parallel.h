// Deterministic chunked parallelism for the cullide module: thin forwards to raster's parallel-for
// (raster/detail/parallel.h), so cullide and raster share one executor and one thread-count rule.
//
// The caller owns threading (house style, after Box2D): an operation takes a thread count, splits its
// work into chunks whose boundaries depend only on the input (never on the thread count), runs them
// in a oneTBB arena of that size (or serially when built without TBB), and merges the per-chunk
// results in chunk order. So the output is the same bits for any thread count.
#pragma once

#include <cstddef>
#include <functional>

namespace cullide::detail {

// Effective worker count: `threads` > 0 as given, 0 = all hardware threads. Serial builds: 1.
[[nodiscard]] int effective_threads(int threads);

// Calls fn(c) once for every c in [0, chunks), on up to `threads` threads. fn must only write
// state owned by chunk c.
void parallel_chunks(int threads, std::size_t chunks, const std::function<void(std::size_t)>& fn);

}  // namespace cullide::detail

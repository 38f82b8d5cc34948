// Stage 2: a stable LSD radix sort, parallel over fixed chunks.
//
// GPU Gems 3 ch. 32 sorts the cell-ID array with a parallel radix sort; its stability is what keeps
// H entries ahead of P entries inside a cell. Per pass: every chunk builds a 256-bin histogram of
// its digit, the histograms are merged in (digit, chunk) order into scatter offsets, and each chunk
// scatters its elements in order. Chunks are fixed-size, so the result (unique for a stable sort
// anyway) is produced by the same steps for any thread count.
#include <algorithm>
#include <cassert>
#include <array>
#include <cstdint>
#include <vector>

#include "spatialhash/detail/grid_stages.h"

namespace spatialhash::detail {

namespace {
constexpr unsigned kDigitBits = 8;
constexpr std::size_t kBins = std::size_t{1} << kDigitBits;
using Histogram = std::array<std::size_t, kBins>;
}  // namespace

void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                Executor& ex) {
    const std::size_t n = keys.size();
    const bool with_values = !values.empty();
    assert(!with_values || values.size() == n);
    if (n < 2 || key_bits == 0) return;
    const std::size_t chunks = chunk_count(n);
    std::vector<Histogram> hist(chunks);
    std::vector<std::uint64_t> keys_tmp(n);
    std::vector<std::uint32_t> values_tmp(with_values ? n : 0);

    for (unsigned shift = 0; shift < key_bits && shift < 64; shift += kDigitBits) {
        ex.for_each(chunks, [&](std::size_t c) {
            Histogram& h = hist[c];
            h.fill(0);
            const std::size_t end = std::min(n, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) ++h[(keys[i] >> shift) & (kBins - 1)];
        });
        // Merge in (digit, chunk) order: the offsets that make the scatter stable.
        std::size_t running = 0;
        bool all_one_digit = false;
        for (std::size_t d = 0; d < kBins; ++d) {
            std::size_t digit_total = 0;
            for (std::size_t c = 0; c < chunks; ++c) {
                const std::size_t count = hist[c][d];
                hist[c][d] = running;
                running += count;
                digit_total += count;
            }
            if (digit_total == n) all_one_digit = true;
        }
        if (all_one_digit) continue;  // every key has this digit: the pass would be the identity
        ex.for_each(chunks, [&](std::size_t c) {
            Histogram& offset = hist[c];
            const std::size_t end = std::min(n, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) {
                const std::size_t dst = offset[(keys[i] >> shift) & (kBins - 1)]++;
                keys_tmp[dst] = keys[i];
                if (with_values) values_tmp[dst] = values[i];
            }
        });
        keys.swap(keys_tmp);
        if (with_values) values.swap(values_tmp);
    }
}

}  // namespace spatialhash::detail

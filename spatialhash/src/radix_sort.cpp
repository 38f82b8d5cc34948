// Stage 2: a stable LSD radix sort, parallel over fixed chunks.
//
// GPU Gems 3 ch. 32 sorts the cell-ID array with a parallel radix sort; its stability is what keeps
// H entries ahead of P entries inside a cell. Per pass: every chunk builds a 256-bin histogram of
// its digit, the histograms are merged in (digit, chunk) order into scatter offsets, and each chunk
// scatters its elements in order. Chunks are fixed-size, so the result (unique for a stable sort
// anyway) is produced by the same steps for any thread count.
#include <algorithm>
#include <cassert>
#include <cstdint>
#include <vector>

#include "spatialhash/detail/grid_stages.h"

namespace spatialhash::detail {

namespace {
// Digits are at most kMaxDigitBits wide, and as wide as needed to cover key_bits in the fewest
// passes (a 16-bit key takes 2 passes of 8 bits, a 19-bit key 2 passes of 10, not 3 of 8).
// 2^11 bins of 8 bytes per chunk still sit in L1/L2 next to the chunk.
constexpr unsigned kMaxDigitBits = 11;
}  // namespace

void radix_sort(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned key_bits,
                Executor& ex) {
    RadixScratch scratch;
    radix_sort_bits(keys, values, 0, key_bits, ex, scratch);
}

void radix_sort_bits(std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& values, unsigned first_bit,
                     unsigned end_bit, Executor& ex, RadixScratch& scratch) {
    const std::size_t n = keys.size();
    const bool with_values = !values.empty();
    assert(!with_values || values.size() == n);
    end_bit = std::min(end_bit, 64U);
    if (n < 2 || end_bit <= first_bit) return;
    const unsigned key_bits = end_bit - first_bit;
    const unsigned passes = (key_bits + kMaxDigitBits - 1) / kMaxDigitBits;
    const unsigned digit_bits = (key_bits + passes - 1) / passes;
    const std::size_t bins = std::size_t{1} << digit_bits;
    const std::uint64_t digit_mask = bins - 1;
    const std::size_t chunks = chunk_count(n);
    // chunk c's bins at [c * bins, (c + 1) * bins). The scratch arrays keep their capacity between
    // calls (a Workspace reuses them frame after frame); resize never shrinks it.
    std::vector<std::size_t>& hist = scratch.hist;
    std::vector<std::uint64_t>& keys_tmp = scratch.keys;
    std::vector<std::uint32_t>& values_tmp = scratch.values;
    hist.resize(chunks * bins);
    keys_tmp.resize(n);
    values_tmp.resize(with_values ? n : 0);

    for (unsigned shift = first_bit; shift < end_bit; shift += digit_bits) {
        ex.for_each(chunks, [&](std::size_t c) {
            std::size_t* h = hist.data() + c * bins;
            std::fill(h, h + bins, std::size_t{0});
            const std::size_t end = std::min(n, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) ++h[(keys[i] >> shift) & digit_mask];
        });
        // Merge in (digit, chunk) order: the offsets that make the scatter stable. Chunk c's offset
        // for digit d is the start of digit d plus the counts of d in chunks before c. Walked
        // chunk by chunk (rows in memory order): the same offsets as a walk down each digit's
        // column, without a cache miss per step (at 13M keys a column walk strides 800 rows of 8 KB).
        std::vector<std::size_t>& running = scratch.digit_start;
        running.assign(bins, 0);
        for (std::size_t c = 0; c < chunks; ++c) {
            const std::size_t* h = hist.data() + c * bins;
            for (std::size_t d = 0; d < bins; ++d) running[d] += h[d];
        }
        bool all_one_digit = false;
        std::size_t start = 0;
        for (std::size_t d = 0; d < bins; ++d) {
            const std::size_t total = running[d];
            if (total == n) all_one_digit = true;
            running[d] = start;
            start += total;
        }
        for (std::size_t c = 0; c < chunks && !all_one_digit; ++c) {
            std::size_t* h = hist.data() + c * bins;
            for (std::size_t d = 0; d < bins; ++d) {
                const std::size_t count = h[d];
                h[d] = running[d];
                running[d] += count;
            }
        }
        if (all_one_digit) continue;  // every key has this digit: the pass would be the identity
        ex.for_each(chunks, [&](std::size_t c) {
            std::size_t* offset = hist.data() + c * bins;
            const std::size_t end = std::min(n, (c + 1) * kChunk);
            for (std::size_t i = c * kChunk; i < end; ++i) {
                const std::size_t dst = offset[(keys[i] >> shift) & digit_mask]++;
                keys_tmp[dst] = keys[i];
                if (with_values) values_tmp[dst] = values[i];
            }
        });
        keys.swap(keys_tmp);
        if (with_values) values.swap(values_tmp);
    }
}

}  // namespace spatialhash::detail

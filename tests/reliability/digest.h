// digest.h: FNV-1a (64-bit) digests of the results the reliability tests pin (tests only).
//
// Every integer is fed as little-endian bytes of a fixed width, so a digest is the same on every
// platform and standard library; doubles and floats by their IEEE bits.
#pragma once

#include <bit>
#include <cstdint>
#include <cstdlib>
#include <string_view>
#include <span>

#include "cullide/ground_truth.h"

namespace reliability {

class Digest {
   public:
    Digest& u64(std::uint64_t v) { return bytes(v, 8); }
    Digest& u32(std::uint32_t v) { return bytes(v, 4); }
    Digest& f64(double v) { return u64(std::bit_cast<std::uint64_t>(v)); }
    Digest& f32(float v) { return u32(std::bit_cast<std::uint32_t>(v)); }
    // The count, then each pair as (object_a, triangle_a, object_b, triangle_b), 4 bytes each.
    Digest& pairs(std::span<const cullide::TrianglePair> list) {
        u64(list.size());
        for (const auto& p : list) u32(p.object_a).u32(p.triangle_a).u32(p.object_b).u32(p.triangle_b);
        return *this;
    }
    [[nodiscard]] std::uint64_t value() const { return h_; }

   private:
    Digest& bytes(std::uint64_t v, int n) {
        for (int i = 0; i < n; ++i) {
            h_ ^= (v >> (8 * i)) & 0xffu;
            h_ *= 0x100000001b3ull;
        }
        return *this;
    }
    std::uint64_t h_ = 0xcbf29ce484222325ull;
};

// CULLIDE_RELIABILITY_QUICK set and not "0": emulated or sanitized runs leave the O(n^2) twins and the
// many-object transforms to the native run (scripts/cross-aarch64.sh and scripts/tsan.sh set it).
[[nodiscard]] inline bool quick_mode() {
    const char* v = std::getenv("CULLIDE_RELIABILITY_QUICK");
    return v != nullptr && *v != '\0' && std::string_view(v) != "0";
}

// The methods of cullide::method_names() that promise never to miss a collision (pipeline.h):
// the reliability tests assert they report exactly the ground truth. The others (exact itself, and
// the GL-exact ones: cullide, qcullide-gl) are not in this list; a new reliable method is added here.
[[nodiscard]] inline bool reliable_method(std::string_view method) {
    return method == "rcullide" || method == "rcullide-offset" || method == "qcullide" || method == "auto";
}

}  // namespace reliability

// libFuzzer target for spatialhash::find_pairs. Property: for any input the three methods agree
// exactly, on the pairs or on the error message (validation errors are the same for all); the
// grid's only error of its own, the key-limit guard, must never fire on input that validates.
// Both boxes and spheres, automatic and given cell sizes, 1-3 threads; the grid also through one
// Workspace reused across all inputs.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "spatialhash/broad_phase.h"

namespace {

class Reader {
   public:
    Reader(const std::uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
    [[nodiscard]] bool empty() const { return p_ == end_; }
    std::uint8_t byte() { return p_ == end_ ? 0 : *p_++; }
    // A coordinate drawn from values that matter: a coarse lattice (exact touching, cell
    // boundaries), fractions, specials, and raw doubles.
    double value() {
        const std::uint8_t mode = byte();
        switch (mode & 3U) {
            case 0:
                return static_cast<double>(static_cast<int>(byte()) - 128) * 0.25;
            case 1:
                return static_cast<double>(byte()) / 255.0 * std::ldexp(1.0, static_cast<int>(mode >> 2) - 32);
            case 2: {
                static const double kSpecial[] = {0.0,     -0.0,   1.0,     -1.0,    1e300,  -1e300, 1e150,
                                                  1e-300,  2097152.0, 0x1.0p52, 1e15, std::numeric_limits<double>::infinity(),
                                                  std::numeric_limits<double>::quiet_NaN(), 0.5, 3.0, 1e7};
                return kSpecial[(mode >> 2) % (sizeof kSpecial / sizeof kSpecial[0])];
            }
            default: {
                double v = 0.0;
                std::uint8_t raw[8];
                for (std::uint8_t& b : raw) b = byte();
                std::memcpy(&v, raw, sizeof v);
                return v;
            }
        }
    }

   private:
    const std::uint8_t* p_;
    const std::uint8_t* end_;
};

template <class Shape>
void check(const std::vector<Shape>& shapes, double cell, unsigned threads) {
    using spatialhash::Method;
    spatialhash::Options o;
    o.threads = threads;
    o.method = Method::BruteForce;
    const auto brute = spatialhash::find_pairs(std::span<const Shape>(shapes), o);
    o.method = Method::SweepAndPrune;
    const auto sap = spatialhash::find_pairs(std::span<const Shape>(shapes), o);
    o.method = Method::SpatialHash;
    o.cell_size = cell;
    const auto grid = spatialhash::find_pairs(std::span<const Shape>(shapes), o);
    o.cell_size = 0.0;  // the twins ignore it, but validation must see the same options
    if (!grid.ok() && brute.ok() && cell != 0.0) {
        // A bad given cell size fails validation for the grid only when it is not the twins' business.
        std::fprintf(stderr, "grid failed alone: %s\n", grid.error().message.c_str());
        std::abort();
    }
    if (brute.ok() != sap.ok() || (grid.ok() != brute.ok())) {
        std::fprintf(stderr, "methods disagree on success: brute %d sap %d grid %d: %s\n", brute.ok(), sap.ok(),
                     grid.ok(), (!grid.ok() ? grid.error().message : !brute.ok() ? brute.error().message : "").c_str());
        std::abort();
    }
    if (!brute.ok()) {
        if (brute.error().message != sap.error().message || brute.error().message != grid.error().message) {
            std::fprintf(stderr, "error messages differ:\n%s\n%s\n%s\n", brute.error().message.c_str(),
                         sap.error().message.c_str(), grid.error().message.c_str());
            std::abort();
        }
        return;
    }
    if (!(sap.value().pairs == brute.value().pairs) || !(grid.value().pairs == brute.value().pairs)) {
        std::fprintf(stderr, "pairs differ: brute %zu sap %zu grid %zu\n", brute.value().pairs.size(),
                     sap.value().pairs.size(), grid.value().pairs.size());
        std::abort();
    }
    // The same through one Workspace kept for the whole fuzzing run: whatever earlier inputs left in
    // its buffers must not change the pairs.
    static spatialhash::Workspace workspace;
    static std::vector<spatialhash::Pair> reused;
    o.cell_size = cell;
    const auto via_workspace = spatialhash::find_pairs(std::span<const Shape>(shapes), o, workspace, reused);
    if (!via_workspace.ok() || !(reused == brute.value().pairs)) {
        std::fprintf(stderr, "workspace pairs differ: %zu vs %zu\n", reused.size(), brute.value().pairs.size());
        std::abort();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Reader in(data, size);
    const std::uint8_t head = in.byte();
    const bool spheres = (head & 1U) != 0;
    const unsigned threads = 1 + (head >> 1) % 3;
    // Cell size: automatic, or a positive value from the input (a bad one is skipped: it would be a
    // grid-only validation error, covered by the unit tests).
    double cell = 0.0;
    if ((head >> 3) & 1U) {
        cell = std::fabs(in.value());
        if (!(std::isfinite(cell) && cell > 0.0)) cell = 0.0;
    }
    const std::size_t n = in.byte() % 48;
    if (spheres) {
        std::vector<spatialhash::Sphere> s;
        for (std::size_t i = 0; i < n && !in.empty(); ++i) {
            spatialhash::Sphere sp{{in.value(), in.value(), in.value()}, std::fabs(in.value())};
            s.push_back(sp);
        }
        check(s, cell, threads);
    } else {
        std::vector<spatialhash::Box> s;
        for (std::size_t i = 0; i < n && !in.empty(); ++i) {
            spatialhash::Box b{};
            const bool ordered = (in.byte() & 7U) != 0;  // mostly valid boxes, sometimes raw (lo > hi)
            for (int k = 0; k < 3; ++k) {
                const double a = in.value();
                const double e = in.value();
                b.lo[k] = a;
                b.hi[k] = ordered ? a + std::fabs(e) : e;
            }
            s.push_back(b);
        }
        check(s, cell, threads);
    }
    return 0;
}

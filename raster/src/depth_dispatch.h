// depth_dispatch.h (private): what every raster kernel is told about a draw (its depth state, the
// depth buffer, the pixel rectangle), GL's depth comparison, and the one dispatch from the runtime
// depth state to a kernel compiled for it.
//
// Every kernel (portable and AVX2 GL-exact, exact bounds) is a template on (format, depth function,
// depth write) so that the per-pixel test is a constant comparison and the write a constant branch;
// dispatch_depth maps the draw's runtime state to one of those 48 instantiations. Kernels pass it a
// functor whose call operator is templated on the three (a lambda `[&]<DepthFormat Fmt, DepthFunc F,
// bool Write>() { ... }`), and may collapse instantiations they do not need (exact bounds).
//
// The AVX2 kernel's translation unit is compiled with -mavx2 and includes this header, so the plain
// inline functions here are always_inline: no out-of-line copy compiled with AVX2 may be emitted
// and chosen by the linker for a portable caller. (The dispatch templates are instantiated on each
// kernel's own lambda type, so their copies are distinct per kernel.)
#pragma once

#include <cstddef>
#include <cstdint>

#include "raster/types.h"

namespace raster::detail {

// glDepthFunc and glDepthMask of a draw, in the target's format.
struct DepthState {
    DepthFormat format;
    DepthFunc func;
    bool write;
};

// A row-major depth buffer with `stride` values per row (the target's width).
struct DepthRows {
    std::uint32_t* values;
    int stride;

    [[gnu::always_inline]] std::uint32_t* row(int y) const {
        return values + static_cast<std::size_t>(y) * static_cast<std::size_t>(stride);
    }
};

// The inclusive pixel rectangle [x0, x1] x [y0, y1] (inside the target). Passed by value: a
// reference would alias the depth stores (int and uint32_t may alias), and the kernels would then
// reload its bounds after every store (the portable kernel was 3% slower on large triangles).
struct PixelRect {
    int x0, y0, x1, y1;
};

// GL's depth test of an incoming value against the stored one (unsigned encodings or floats).
template <DepthFunc F, class T>
[[gnu::always_inline]] inline bool depth_pass(T incoming, T stored) {
    if constexpr (F == DepthFunc::Never) return false;
    if constexpr (F == DepthFunc::Less) return incoming < stored;
    if constexpr (F == DepthFunc::Equal) return incoming == stored;
    if constexpr (F == DepthFunc::LEqual) return incoming <= stored;
    if constexpr (F == DepthFunc::Greater) return incoming > stored;
    if constexpr (F == DepthFunc::NotEqual) return incoming != stored;
    if constexpr (F == DepthFunc::GEqual) return incoming >= stored;
    if constexpr (F == DepthFunc::Always) return true;
    return false;
}

namespace dispatch {

template <class R, DepthFormat Fmt, DepthFunc F, class Kernel>
R by_write(bool write, Kernel& kernel) {
    return write ? kernel.template operator()<Fmt, F, true>() : kernel.template operator()<Fmt, F, false>();
}

template <class R, DepthFormat Fmt, class Kernel>
R by_func(DepthFunc func, bool write, Kernel& kernel) {
    switch (func) {
        case DepthFunc::Never: return by_write<R, Fmt, DepthFunc::Never>(write, kernel);
        case DepthFunc::Less: return by_write<R, Fmt, DepthFunc::Less>(write, kernel);
        case DepthFunc::Equal: return by_write<R, Fmt, DepthFunc::Equal>(write, kernel);
        case DepthFunc::LEqual: return by_write<R, Fmt, DepthFunc::LEqual>(write, kernel);
        case DepthFunc::Greater: return by_write<R, Fmt, DepthFunc::Greater>(write, kernel);
        case DepthFunc::NotEqual: return by_write<R, Fmt, DepthFunc::NotEqual>(write, kernel);
        case DepthFunc::GEqual: return by_write<R, Fmt, DepthFunc::GEqual>(write, kernel);
        case DepthFunc::Always: return by_write<R, Fmt, DepthFunc::Always>(write, kernel);
    }
    return R{};
}

}  // namespace dispatch

// Returns kernel.operator()<state.format, state.func, state.write>(): the samples that passed, or
// (R other than the default) what the kernel functor returns, e.g. a pointer to an instantiation.
template <class R = std::uint64_t, class Kernel>
R dispatch_depth(const DepthState& state, Kernel&& kernel) {
    switch (state.format) {
        case DepthFormat::D16: return dispatch::by_func<R, DepthFormat::D16>(state.func, state.write, kernel);
        case DepthFormat::D24: return dispatch::by_func<R, DepthFormat::D24>(state.func, state.write, kernel);
        case DepthFormat::D32F: return dispatch::by_func<R, DepthFormat::D32F>(state.func, state.write, kernel);
    }
    return R{};
}

}  // namespace raster::detail

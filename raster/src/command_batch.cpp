// command_batch.cpp: recording and up-front validation of a command batch.
#include "raster/command_batch.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "validate.h"

namespace raster {

void CommandBatch::draw(MeshView mesh, const DrawState& state) {
    Command c;
    c.kind = Command::Kind::Draw;
    c.mesh = mesh;
    c.state = state;
    commands_.push_back(c);
}

void CommandBatch::draw(MeshViewD mesh, const DrawState& state) {
    Command c;
    c.kind = Command::Kind::Draw;
    c.mesh_d = mesh;
    c.double_input = true;
    c.state = state;
    commands_.push_back(c);
}

std::uint32_t CommandBatch::begin_query(QueryKind kind) {
    const auto index = static_cast<std::uint32_t>(query_kinds_.size());
    query_kinds_.push_back(kind);
    Command c;
    c.kind = Command::Kind::BeginQuery;
    c.query = index;
    commands_.push_back(c);
    return index;
}

void CommandBatch::end_query() {
    Command c;
    c.kind = Command::Kind::EndQuery;
    commands_.push_back(c);
}

void CommandBatch::clear() {
    commands_.clear();
    query_kinds_.clear();
}

void CommandBatch::reset(int target_width, int target_height, RasterRules rules) {
    clear();
    width_ = target_width;
    height_ = target_height;
    rules_ = rules;
}

namespace detail {

namespace {
bool finite4(const Float4& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}

// The exact-bounds rules for one vertex (floats are checked after their exact widening to double).
std::string check_exact_bounds_vertex(double x, double y, double z, double w) {
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) || !std::isfinite(w)) return "is not finite";
    if (w != 1.0) return "has w = " + std::to_string(w) + " (the exact-bounds mode takes orthographic input, w = 1)";
    if (std::fabs(x) > kMaxExactBoundsCoordinate || std::fabs(y) > kMaxExactBoundsCoordinate ||
        std::fabs(z) > kMaxExactBoundsCoordinate)
        return "has a coordinate beyond +-2^100 (kMaxExactBoundsCoordinate)";
    return {};
}
std::string cmd_name(std::size_t i) { return "command " + std::to_string(i); }

// Whether every vertex of a whole list passes its draw's per-vertex rule (below), without naming
// one: a straight pass over the list with no message, which the per-index loop's gathers and error
// branches cost several times over (validation was 5% of a cylinders / cullide frame's
// instructions: callgrind, issue #17).
// Branch-free over the bits: a component is finite iff its exponent bits are not all ones, and
// (0, 0, 0, 0) has every component +-0 (the same rules as finite4 and the zero test below).
bool gl_list_valid(std::span<const Float4> verts) {
    static_assert(sizeof(Float4) == 16);
#if defined(__SSE2__)
    // One vertex per 128-bit register (the compiler kept the loop below scalar: 5.6% of raster_bench
    // SmallTris 1024^2 at one thread, perf): |bits| = bits & 0x7fffffff per component; a component
    // is not finite iff |bits| >= 0x7f800000 (signed compare: |bits| < 2^31), and the vertex is
    // (0, 0, 0, 0) iff the OR of its four |bits| is 0.
    const __m128i abs_mask = _mm_set1_epi32(0x7fffffff);
    const __m128i inf_minus_1 = _mm_set1_epi32(0x7f7fffff);
    __m128i bad_v = _mm_setzero_si128();
    for (const Float4& v : verts) {
        const __m128i a = _mm_and_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(&v)), abs_mask);
        __m128i any = _mm_or_si128(a, _mm_shuffle_epi32(a, 0x4e));  // lanes (0|2, 1|3, 2|0, 3|1)
        any = _mm_or_si128(any, _mm_shuffle_epi32(any, 0xb1));      // every lane: the OR of all four
        bad_v = _mm_or_si128(bad_v, _mm_cmpgt_epi32(a, inf_minus_1));
        bad_v = _mm_or_si128(bad_v, _mm_cmpeq_epi32(any, _mm_setzero_si128()));
    }
    return _mm_movemask_epi8(bad_v) == 0;
#else
    std::uint32_t bad = 0;
    for (const Float4& v : verts) {
        std::uint32_t b[4];
        std::memcpy(b, &v, sizeof b);
        const std::uint32_t e = 0x7f800000u;
        const std::uint32_t nonfinite = static_cast<std::uint32_t>((b[0] & e) == e) | static_cast<std::uint32_t>((b[1] & e) == e) |
                                        static_cast<std::uint32_t>((b[2] & e) == e) | static_cast<std::uint32_t>((b[3] & e) == e);
        const std::uint32_t zero = static_cast<std::uint32_t>(((b[0] | b[1] | b[2] | b[3]) & 0x7fffffffu) == 0);
        bad |= nonfinite | zero;
    }
    return bad == 0;
#endif
}
template <class V>
bool exact_bounds_list_valid(std::span<const V> verts) {
    bool ok = true;
    for (const V& v : verts) {
        const double x = static_cast<double>(v.x), y = static_cast<double>(v.y), z = static_cast<double>(v.z);
        // The comparisons are false for NaN, and an infinity exceeds the bound: check_exact_bounds_vertex's rules.
        ok = ok && static_cast<double>(v.w) == 1.0 && std::fabs(x) <= kMaxExactBoundsCoordinate &&
             std::fabs(y) <= kMaxExactBoundsCoordinate && std::fabs(z) <= kMaxExactBoundsCoordinate;
    }
    return ok;
}
// Whether every index is below n (a count of offenders, which vectorizes; a running maximum of
// unsigned values does not on baseline x86-64, which has no unsigned 32-bit max).
bool indices_below(std::span<const std::uint32_t> idx, std::size_t n) {
    if (n > UINT32_MAX) return true;
    const auto m = static_cast<std::uint32_t>(n);
    std::uint32_t over = 0;
    for (const std::uint32_t k : idx) over |= static_cast<std::uint32_t>(k >= m);
    return over == 0;
}

// The vertex lists of a sequence's batches already found wholly valid. Draws that index one list in
// many pieces (CULLIDE's sub-objects: 12 of an object's indices per draw) check it once; the last
// kEntries lists are kept, as each CULLIDE pass alternates between its objects' lists (one kept list
// checked the cloth's two lists twice per pass: 6% of a cloth / rcullide-offset frame, serial). A
// whole list costs its length, so it is checked only within an allowance of four vertices per index
// validated so far: small draws into many large lists cost at most a few times the per-index loop,
// never their list sizes over and over.
class ListMemo {
   public:
    // Whether `verts` (first vertex `data`, `size` of them) is known or now found valid; `check`
    // tests the whole list. `indices` is the draw's index count.
    template <class Check>
    bool valid(const void* data, std::size_t size, std::size_t indices, const Check& check) {
        allowance_ += 4 * indices;
        for (const Entry& e : known_)
            if (data == e.data && size <= e.size) return true;
        if (size > allowance_) return false;
        allowance_ -= size;
        if (!check()) return false;
        known_[next_] = {data, size};
        next_ = (next_ + 1) % kEntries;
        return true;
    }

   private:
    static constexpr std::size_t kEntries = 8;
    struct Entry {
        const void* data = nullptr;
        std::size_t size = 0;
    };
    std::array<Entry, kEntries> known_{};
    std::size_t next_ = 0;
    std::size_t allowance_ = 0;
};

// The lists of each vertex rule, kept over a sequence's batches.
struct ListMemos {
    ListMemo gl, bounds, bounds_d;
};

Status validate_with(const DepthTarget& target, const CommandBatch& batch, ListMemos& memos);
}  // namespace

Status validate(const DepthTarget& target, const CommandBatch& batch) {
    ListMemos memos;
    return validate_with(target, batch, memos);
}

SequenceCheck validate_sequence(const DepthTarget& target, std::span<const CommandBatch* const> batches) {
    ListMemos memos;
    for (std::size_t k = 0; k < batches.size(); ++k)
        if (Status s = validate_with(target, *batches[k], memos); !s) return {k, std::move(s)};
    return {batches.size(), {}};
}

namespace {
Status validate_with(const DepthTarget& target, const CommandBatch& batch, ListMemos& memos) {
    if (batch.target_width() != target.width() || batch.target_height() != target.height()) {
        return Error{"batch was built for a " + std::to_string(batch.target_width()) + "x" +
                     std::to_string(batch.target_height()) + " target but the target is " +
                     std::to_string(target.width()) + "x" + std::to_string(target.height())};
    }
    bool active = false;
    ListMemo &gl_lists = memos.gl, &bounds_lists = memos.bounds, &bounds_lists_d = memos.bounds_d;
    const auto& cmds = batch.commands();
    for (std::size_t i = 0; i < cmds.size(); ++i) {
        const Command& c = cmds[i];
        switch (c.kind) {
            case Command::Kind::BeginQuery:
                if (active) return Error{cmd_name(i) + ": begin_query while another query is active (queries do not nest)"};
                active = true;
                break;
            case Command::Kind::EndQuery:
                if (!active) return Error{cmd_name(i) + ": end_query without an active query"};
                active = false;
                break;
            case Command::Kind::Draw: {
                const DrawState& s = c.state;
                if (s.mode != RasterMode::GLExact && s.mode != RasterMode::ExactBounds)
                    return Error{cmd_name(i) + ": unsupported raster mode " + std::to_string(static_cast<int>(s.mode))};
                if (c.double_input && s.mode != RasterMode::ExactBounds)
                    return Error{cmd_name(i) + ": a double-precision draw (MeshViewD) needs RasterMode::ExactBounds"};
                if (static_cast<unsigned>(s.depth_func) > static_cast<unsigned>(DepthFunc::Always))
                    return Error{cmd_name(i) + ": invalid depth function"};
                if (static_cast<unsigned>(s.cull_face) > static_cast<unsigned>(CullFace::Back) ||
                    static_cast<unsigned>(s.front_face) > static_cast<unsigned>(FrontFace::CW))
                    return Error{cmd_name(i) + ": invalid cull/front face"};
                if (s.mode == RasterMode::ExactBounds && s.cull_face != CullFace::None)
                    return Error{cmd_name(i) + ": RasterMode::ExactBounds needs CullFace::None (an edge-on triangle "
                                               "has no facing, and a conservative mode may not drop it)"};
                if (s.viewport) {
                    const Viewport& v = *s.viewport;
                    if (v.width < 1 || v.height < 1 || v.width > kMaxTargetSize || v.height > kMaxTargetSize ||
                        v.x < -kMaxTargetSize || v.x > kMaxTargetSize || v.y < -kMaxTargetSize || v.y > kMaxTargetSize) {
                        return Error{cmd_name(i) + ": viewport (" + std::to_string(v.x) + ", " + std::to_string(v.y) +
                                     ", " + std::to_string(v.width) + ", " + std::to_string(v.height) +
                                     ") is outside the limits (size 1.." + std::to_string(kMaxTargetSize) +
                                     ", origin within +-" + std::to_string(kMaxTargetSize) + ")"};
                    }
                }
                const auto& idx = c.double_input ? c.mesh_d.indices : c.mesh.indices;
                const std::size_t vertex_count = c.double_input ? c.mesh_d.vertices.size() : c.mesh.vertices.size();
                if (idx.size() % 3 != 0) {
                    return Error{cmd_name(i) + ": index count " + std::to_string(idx.size()) + " is not a multiple of 3"};
                }
                // Fast path: every index in range and the whole vertex list valid (known from an
                // earlier draw of the batch, or checked now). Otherwise the loop below finds the
                // first offence and names it; it checks only the vertices that triangles use (a
                // shared vertex list may hold others), so a list with an invalid unused vertex is
                // still accepted, only more slowly.
                {
                    bool list_ok = false;
                    if (indices_below(idx, vertex_count)) {
                        if (c.double_input) {
                            const auto verts = c.mesh_d.vertices;
                            list_ok = bounds_lists_d.valid(verts.data(), verts.size(), idx.size(),
                                                           [&] { return exact_bounds_list_valid(verts); });
                        } else if (s.mode == RasterMode::ExactBounds) {
                            const auto verts = c.mesh.vertices;
                            list_ok = bounds_lists.valid(verts.data(), verts.size(), idx.size(),
                                                         [&] { return exact_bounds_list_valid(verts); });
                        } else {
                            const auto verts = c.mesh.vertices;
                            list_ok = gl_lists.valid(verts.data(), verts.size(), idx.size(),
                                                     [&] { return gl_list_valid(verts); });
                        }
                    }
                    if (list_ok) break;
                }
                for (std::size_t k = 0; k < idx.size(); ++k) {
                    if (idx[k] >= vertex_count) {
                        return Error{cmd_name(i) + ": index " + std::to_string(idx[k]) + " at position " +
                                     std::to_string(k) + " is beyond the vertex list (size " +
                                     std::to_string(vertex_count) + ")"};
                    }
                    if (s.mode == RasterMode::ExactBounds) {
                        std::string why;
                        if (c.double_input) {
                            const Double4& d = c.mesh_d.vertices[idx[k]];
                            why = check_exact_bounds_vertex(d.x, d.y, d.z, d.w);
                        } else {
                            const Float4& f = c.mesh.vertices[idx[k]];
                            why = check_exact_bounds_vertex(static_cast<double>(f.x), static_cast<double>(f.y),
                                                            static_cast<double>(f.z), static_cast<double>(f.w));
                        }
                        if (!why.empty()) return Error{cmd_name(i) + ": vertex " + std::to_string(idx[k]) + " " + why};
                        continue;
                    }
                    const Float4& v = c.mesh.vertices[idx[k]];
                    if (!finite4(v)) return Error{cmd_name(i) + ": vertex " + std::to_string(idx[k]) + " is not finite"};
                    if (v.w == 0.0f && v.x == 0.0f && v.y == 0.0f && v.z == 0.0f) {
                        return Error{cmd_name(i) + ": vertex " + std::to_string(idx[k]) +
                                     " is (0, 0, 0, 0), which has no window position"};
                    }
                }
                break;
            }
            default:
                return Error{cmd_name(i) + ": unknown command kind"};
        }
    }
    if (active) return Error{"the batch ends with a query still active (missing end_query)"};
    return {};
}
}  // namespace

}  // namespace detail
}  // namespace raster

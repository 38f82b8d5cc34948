// raster/command_batch.h: draws and occlusion queries recorded in GL order, executed in one pass.
// Conventions: raster/raster.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "raster/depth_target.h"
#include "raster/result.h"
#include "raster/types.h"

namespace raster {

// One recorded command. Draw: mesh (float input) or mesh_d (double input, when double_input) +
// state. BeginQuery/EndQuery: the query with index `query`.
struct Command {
    enum class Kind : std::uint8_t { Draw, BeginQuery, EndQuery };
    Kind kind = Kind::Draw;
    std::uint32_t query = 0;
    MeshView mesh;
    MeshViewD mesh_d;
    bool double_input = false;
    DrawState state;
};

// A command list for a target of one size. Recording never fails; execute() validates everything
// first and reports the first problem (naming the command, the element and the limit).
class CommandBatch {
   public:
    CommandBatch(int target_width, int target_height, RasterRules rules = RasterRules::GlLlvmpipe)
        : width_(target_width), height_(target_height), rules_(rules) {}

    void draw(MeshView mesh, const DrawState& state);
    // Double-precision input for RasterMode::ExactBounds (docs/reliable-raster.md). execute() fails,
    // naming the command, unless state.mode is ExactBounds and every used vertex is finite with
    // w == 1 and |x|, |y|, |z| <= kMaxExactBoundsCoordinate, and state.cull_face is None (an
    // edge-on triangle has no facing). Float input (draw(MeshView, ...)) is accepted in ExactBounds
    // too, under the same rules (floats convert to double exactly).
    void draw(MeshViewD mesh, const DrawState& state);
    // glBeginQuery; returns the query's index into the results of execute().
    std::uint32_t begin_query(QueryKind kind);
    void end_query();                         // glEndQuery of the active query

    [[nodiscard]] int target_width() const { return width_; }
    [[nodiscard]] int target_height() const { return height_; }
    // The API whose rules the batch's GL-exact draws follow (types.h); clear() keeps it.
    [[nodiscard]] RasterRules rules() const { return rules_; }
    [[nodiscard]] const std::vector<Command>& commands() const { return commands_; }
    [[nodiscard]] const std::vector<QueryKind>& query_kinds() const { return query_kinds_; }
    void clear();
    // clear() and a new target size and rules, keeping the memory of the command list: a caller
    // that records a batch per view (CULLIDE's passes: about a hundred thousand commands per
    // frame) reuses one instead of growing a new list, with its page faults, every time.
    void reset(int target_width, int target_height, RasterRules rules = RasterRules::GlLlvmpipe);

   private:
    int width_;
    int height_;
    RasterRules rules_;
    std::vector<Command> commands_;
    std::vector<QueryKind> query_kinds_;
};

// How execute() runs. threads: the worker count, 0 = all hardware threads (the one rule of the
// project: docs/architecture.md, "Threading"); negative counts are an error. The caller owns
// threading, so the default is one. Built without oneTBB, every count runs serially. Results never
// depend on it.
struct ExecuteOptions {
    int threads = 1;
    bool allow_simd = true;  // false: always the portable kernel (tests compare the two)
    // false: execute() tests every pixel (no per-block depth bounds; tests compare the two). The
    // environment variable CULLIDE_RASTER_NO_HIZ (set, not "0") also turns it off, for benchmarks.
    // Results never depend on it.
    bool hierarchical_z = true;
    // When set (execute() only): one entry per kExecuteTileSize square tile of the target, row-major
    // from the bottom left ((width + 63) / 64 per row), each a mask of the tile's 8 x 8 pixel
    // blocks (kExecuteBlockSize): bit by * 8 + bx for the block bx blocks right of and by blocks up
    // from the tile's bottom-left corner (bits of blocks past the target's edge mean nothing).
    // execute() sets the bits of the blocks where a draw with the depth mask on passed the depth
    // test (a superset of the pixels it wrote) and leaves the others as they are, so that a caller
    // can restore only those blocks. Resized to the tile count (new entries 0) when its size differs.
    std::vector<std::uint64_t>* written_blocks = nullptr;
    // When set, every batch runs on a target cleared to this depth: the same results and buffer as
    // DepthTarget::clear(*clear_depth) before each batch (execute_reference does exactly that).
    // The tiled executor fills each tile in the tile's own task, before its first draw there: in
    // parallel, and while the tile is in that core's cache (a separate DepthTarget::clear is one
    // serial pass over the whole buffer). Without written_blocks, the target's own record decides
    // (DepthTarget's fast clear): after a clear to the same depth, only the blocks its draws wrote
    // since are filled. With written_blocks, only the blocks flagged there are
    // filled, and their bits reset before the batch's draws set them again: the caller's promise
    // that the other blocks hold this depth already, which execute() keeps from one call to the
    // next when every call uses the same clear_depth. If written_blocks has to be resized, every
    // block is flagged (its content is unknown). Must be finite (values outside [0, 1] clamp, as
    // DepthTarget::clear).
    std::optional<double> clear_depth = std::nullopt;
    // When set, only the query results are wanted: a draw that no query can observe is skipped,
    // and the target's content afterwards is unspecified (written_blocks still flags every block a
    // draw wrote, so clear_depth's restoring stays exact). The results are the same bit for bit.
    // Skipped: a draw outside every query that writes no pixel a later query of its batch may
    // cover (or writes nothing); and, with clear_depth = 1, a GL-exact draw inside a query, with the
    // mask off, whose test cannot pass against the clear value (GEQUAL, GREATER or EQUAL with every
    // fragment's depth below 1, or NEVER) at pixels no earlier kept write of its batch may cover.
    // "May cover": a box around the draw's vertices, in cells of up to 8 x 8 pixels (execute.cpp,
    // observed_draws). CULLIDE's recorded passes (the emulator device's execute_cleared) set it.
    bool queries_only = false;
};

// The side of execute()'s tiles and of the blocks of ExecuteOptions::written_blocks.
inline constexpr int kExecuteTileSize = 64;
inline constexpr int kExecuteBlockSize = 8;

// True when allow_simd runs a SIMD GL-exact kernel in this process: the AVX2 one was built (x86-64,
// GCC or Clang), the CPU has AVX2 and FMA, and CULLIDE_RASTER_NO_SIMD is unset or 0. For reports
// such as `cullide --version`; results never depend on it (the kernels are bit-identical).
[[nodiscard]] bool simd_kernel_active();
// Which GL-exact kernel allow_simd runs in this process: "AVX-512" (16 pixels per step, where the
// CPU has AVX-512F and VL and CULLIDE_RASTER_NO_AVX512 is unset or 0), "AVX2" or "portable".
[[nodiscard]] const char* simd_kernel_name();

// Query results, indexed like begin_query() returned: samples passed for SamplesPassed queries,
// 0 or 1 for AnySamplesPassed.
using QueryResults = std::vector<std::uint64_t>;

// Tiled execution: the target is split into 64 x 64 tiles, each owned by one task; per-tile
// counters are summed in tile order. Bit-identical to execute_reference for any thread count.
[[nodiscard]] Result<QueryResults> execute(DepthTarget& target, const CommandBatch& batch,
                                           const ExecuteOptions& options = {});

// Several batches on one target, in order: the same results, bits and errors as calling
// between(k) before batch k (k >= 1) and execute(target, *batches[k], options) for each in turn,
// with two differences. All batches are validated first: if one is invalid, none runs (the error
// names it). And the triangle setup (clipping, snapping, edge functions, depth planes) of a draw is
// done once for every draw of any batch with the same vertex and index spans and front-end state
// (viewport, facing, rules; culling is applied per draw). CULLIDE's two passes of a view draw the
// same items in opposite orders, each pass on a cleared target: as one sequence they share their
// setup. Every batch's spans must be alive and unchanged for the whole call (the rule of
// raster/types.h). `between` may change the target's depth values (a clear, for instance) but not
// its size or format, and may not call execute or execute_sequence (refused with an error).
[[nodiscard]] Result<std::vector<QueryResults>> execute_sequence(DepthTarget& target,
                                                                 std::span<const CommandBatch* const> batches,
                                                                 const ExecuteOptions& options = {},
                                                                 const std::function<void(std::size_t)>& between = {});

// The scalar reference: commands one by one, each triangle over its whole bounding box, on one
// thread (options.threads is ignored; allow_simd is honoured).
[[nodiscard]] Result<QueryResults> execute_reference(DepthTarget& target, const CommandBatch& batch,
                                                     const ExecuteOptions& options = {});

}  // namespace raster

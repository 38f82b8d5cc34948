// cullide/hunt.h: searching for frames where a culling method disagrees with the ground truth, and
// shrinking each one to a small reproduction (the engine of `cullide hunt`, docs/hunt.md).
//
// Three parts, each usable alone:
//  - generators: deterministic test frames from a seed, either adversarial triangle soups (contacts
//    that visibility culling finds hard: near-coplanar, grazing, sub-pixel, edge-on walls, slivers,
//    extreme coordinates, an axis-aligned room) or perturbations of a frame the caller gives (mesh
//    files, built-in scene frames);
//  - check: one frame through process_frame and through exact_pairs; a finding is any difference
//    (a missed true pair, or a reported pair the ground truth lacks);
//  - shrink: delta debugging (Zeller and Hildebrandt, "Simplifying and isolating failure-inducing
//    input", IEEE TSE 2002) over objects, then triangles, then coordinate simplification, keeping
//    every step that still disagrees; and classify, which names the reason of a miss by re-running
//    the shrunk frame with changed settings.
// Same seed and options, same frames and same shrunk results, whatever the thread count.
#pragma once

#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "cullide/ground_truth.h"
#include "cullide/mesh.h"
#include "cullide/pipeline.h"
#include "cullide/result.h"
#include "cullide/scenes.h"

namespace cullide::hunt {

// The built-in generators. Each makes a small frame (2-9 objects, at most about 150 triangles)
// around the unit cube, from one 64-bit seed.
enum class Generator {
    Soup,      // random triangles, on a coarse grid or raw doubles
    Coplanar,  // triangles in one plane, or a tiny distance apart (near-coplanar contact)
    Grazing,   // a vertex or an edge exactly on another triangle (touching, no crossing)
    SubPixel,  // a sheet (often tilted off every axis plane) poked through by 2^-7..2^-24
    EdgeOn,    // an axis-aligned wall (seen edge-on in two axis views) crossed by a small solid
    Sliver,    // needle and cap triangles crossing ordinary ones
    Extreme,   // a soup scaled by 2^k (|k| up to 200) or moved by up to 1e6
    Room,      // a box room of six wall objects, and solids crossing its walls
};

[[nodiscard]] const char* to_string(Generator g);
// "soup", "coplanar", ...; the error lists the valid names.
[[nodiscard]] Result<Generator> parse_generator(std::string_view name);
[[nodiscard]] std::vector<std::string> generator_names();
[[nodiscard]] std::vector<Generator> all_generators();

// A frame of generator g for this seed. Every mesh is valid and every coordinate in the exact
// predicates' range.
[[nodiscard]] Frame generate(Generator g, std::uint64_t seed);

// A perturbation of `base` for this seed: unchanged, some vertices moved by a small relative amount,
// one object moved towards another, or every coordinate snapped to a coarse grid (which makes exact
// contacts and pixel-centre ties). Coordinates stay in the exact range.
[[nodiscard]] Frame perturb(const Frame& base, std::uint64_t seed);

// How a method's pairs differ from the ground truth on one frame.
struct Verdict {
    std::vector<TrianglePair> missed;  // true pairs the method did not report
    std::vector<TrianglePair> extra;   // pairs it reported that do not collide
    std::uint64_t truth_pairs = 0;
    [[nodiscard]] bool failed() const { return !missed.empty() || !extra.empty(); }
};

// One frame through `options` (process_frame) and the ground truth (exact_pairs, with options.self).
// Fails when either refuses the frame.
[[nodiscard]] Result<Verdict> check(std::span<const Mesh> objects, const RunOptions& options,
                                    FrameContext& context);

// Asked between checks; true stops the search or the shrinking at once (Ctrl-C, a time budget).
using StopFn = std::function<bool()>;

// Why a method misses, named by re-running the frame with one setting changed (first match wins):
enum class Reason {
    DepthQuantization,  // D16/D24 misses it, D32F at the same resolution does not
    PixelTie,           // a view one pixel larger or smaller catches it: the contact sits on the pixel
                        // grid (a tie at a pixel centre: an edge or an equal depth exactly there)
    SubPixel,           // four times the resolution catches it
    Touching,           // no setting above helps, and every missed pair only touches (tri_tri.h: Touching
                        // or CoplanarOverlap, no crossing): the contact has no volume, so every depth
                        // comparison on it is a tie, at any resolution and depth format
    EdgeOn,             // no setting above helps, not Touching, and in every missed pair a triangle is
                        // seen edge-on (zero area) in an axis view, where the rasterizer covers none of
                        // its pixels (a property of the geometry, not proven to be the cause)
    Unclassified,       // none of the above (also: a never-miss method's disagreement)
};
[[nodiscard]] const char* to_string(Reason r);

struct ShrinkStats {
    std::uint64_t checks = 0;              // frames run while shrinking (a classification counts 4)
    bool stopped = false;                  // the stop function or the check limit ended it early
    Reason reason = Reason::Unclassified;  // classify's reason after the object and triangle stages
};

// Shrinks a failing frame: ddmin over objects, then over all triangles (objects left without one
// are dropped; unused vertices are removed), keeping a step while check() still fails (and, when the
// input misses a crossing pair, tri_tri.h's Crossing, while a crossing pair is still missed); then
// coordinates (the whole frame rounded to a coarser dyadic grid, then each distinct coordinate value,
// everywhere at once, set to 0, rounded to an integer, to a few binary places, or to fewer mantissa
// bits), keeping a step only while the failure keeps its kind: the same classify() reason as before
// this stage, and no more degenerate triangles. At most `max_checks` frames are run (roughly: a
// step in progress finishes). The result fails check() (it is the input when nothing smaller does).
[[nodiscard]] Frame shrink(const Frame& failing, const RunOptions& options, FrameContext& context,
                           const StopFn& stop, std::uint64_t max_checks, ShrinkStats* stats = nullptr);

// The reason of `verdict` (which must come from check(objects, options)). Runs at most four frames;
// Touching and EdgeOn are then decided on the geometry.
[[nodiscard]] Result<Reason> classify(std::span<const Mesh> objects, const Verdict& verdict,
                                      const RunOptions& options, FrameContext& context);

// True when triangle t of m has zero area seen along `axis` (0 = x, 1 = y, 2 = z), exactly.
[[nodiscard]] bool edge_on(const Mesh& m, std::size_t t, int axis);

}  // namespace cullide::hunt

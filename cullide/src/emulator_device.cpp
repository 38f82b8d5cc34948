// emulator_device.cpp: the built-in QueryDevice (emulator_device.h).
#include "emulator_device.h"

#include <algorithm>
#include <cmath>

#include "parallel.h"
#include "raster/visibility.h"

namespace cullide {
namespace detail {
namespace {

// Targets of fewer pixels are cleared in full: below 256 x 256 the fill costs less than working out
// the written spans (qcullide's 32 x 32 views spent 15% of a tiny frame marking, 2% clearing).
constexpr long long kTrackedClearPixels = 256LL * 256;

}  // namespace

EmulatorDevice::EmulatorDevice(int threads) : threads_(effective_threads(threads)) {}

void EmulatorDevice::set_threads(int threads) { threads_ = effective_threads(threads); }

Status EmulatorDevice::clear(int width, int height, raster::DepthFormat format) {
    if (!target_ || target_->width() != width || target_->height() != height || target_->format() != format) {
        raster::Result<raster::DepthTarget> t = raster::DepthTarget::create(width, height, format);
        if (!t) return Error{"emulator device: " + t.error().message};
        target_.emplace(std::move(t).value());
        // A new target is created cleared to 1.0: nothing written yet.
        const bool track = static_cast<long long>(width) * height >= kTrackedClearPixels;
        written_lo_.assign(track ? static_cast<std::size_t>(height) : 0, width);
        written_hi_.assign(track ? static_cast<std::size_t>(height) : 0, -1);
        return Status{};
    }
    if (written_lo_.empty()) {
        if (raster::Status s = target_->clear(1.0); !s) return Error{"emulator device: " + s.error().message};
        return Status{};
    }
    // Only what draws may have written differs from depth 1.0: the same buffer as a full clear.
    const std::uint32_t one = raster::DepthTarget::encode_clear(1.0, format);
    std::span<std::uint32_t> values = target_->mutable_values();
    for (std::size_t y = 0; y < written_lo_.size(); ++y) {
        if (written_lo_[y] > written_hi_[y]) continue;
        const std::size_t row = y * static_cast<std::size_t>(width);
        std::fill(values.begin() + static_cast<std::ptrdiff_t>(row + static_cast<std::size_t>(written_lo_[y])),
                  values.begin() + static_cast<std::ptrdiff_t>(row + static_cast<std::size_t>(written_hi_[y]) + 1),
                  one);
        written_lo_[y] = width;
        written_hi_[y] = -1;
    }
    return Status{};
}

void EmulatorDevice::mark(int y, int x0, int x1) {
    const std::size_t row = static_cast<std::size_t>(y);
    written_lo_[row] = std::min(written_lo_[row], std::max(x0, 0));
    written_hi_[row] = std::max(written_hi_[row], std::min(x1, target_->width() - 1));
}

void EmulatorDevice::mark_all() {
    for (int y = 0; y < target_->height(); ++y) mark(y, 0, target_->width() - 1);
}

namespace {

// Window position of a clip-space vertex with w == 1 (raster/raster.h, the viewport transform of the
// whole target), in double: it differs from the rasterizer's float arithmetic and 16.8 snapping by
// far less than the pixel margins of mark_triangle.
struct WindowXY {
    double x, y;
};

// Every pixel a triangle can write: GL-exact writes pixels whose centre it covers, exact-bounds
// pixels whose closed square it meets; both lie in the triangle's bounding box, widened by two rows
// and two pixels on each side so that rounding can never put a written pixel outside (clipping only
// shrinks it). The box, not the triangle's own span per row: marking is serial work after every
// batch, and the box costs two compares per row where the exact span cost six edge intersections
// (the marking was a quarter of a 1-thread leaves / cullide frame, perf); what the box adds to the
// next clear is a fill of a few pixels per row.
// floor(v) as an int within [lo, hi] (coordinates far outside the target are legal clip input).
int floor_within(double v, int lo, int hi) {
    return v <= lo ? lo : v >= hi ? hi : static_cast<int>(std::floor(v));
}

template <class Mark>
void mark_triangle(const WindowXY (&v)[3], int width, int height, const Mark& mark) {
    const double ylo = std::min({v[0].y, v[1].y, v[2].y});
    const double yhi = std::max({v[0].y, v[1].y, v[2].y});
    const int row0 = std::max(0, floor_within(ylo, -4, height + 4) - 2);
    const int row1 = std::min(height - 1, floor_within(yhi, -4, height + 4) + 2);
    if (row0 > row1) return;
    const int x0 = floor_within(std::min({v[0].x, v[1].x, v[2].x}), -4, width + 4) - 2;
    const int x1 = floor_within(std::max({v[0].x, v[1].x, v[2].x}), -4, width + 4) + 2;
    mark(row0, row1, x0, x1);
}

// Marks the triangles of one draw; false when a vertex is not an orthographic one (w != 1), which
// this bound does not cover.
template <class Vertex, class Mark>
bool mark_draw(std::span<const Vertex> vertices, std::span<const std::uint32_t> indices, int width, int height,
               const Mark& mark) {
    for (std::size_t t = 0; t + 2 < indices.size(); t += 3) {
        WindowXY w[3];
        for (int k = 0; k < 3; ++k) {
            const Vertex& c = vertices[indices[t + static_cast<std::size_t>(k)]];
            if (c.w != 1) return false;
            w[k] = {(static_cast<double>(c.x) + 1.0) * 0.5 * width, (static_cast<double>(c.y) + 1.0) * 0.5 * height};
        }
        mark_triangle(w, width, height, mark);
    }
    return true;
}

}  // namespace

void EmulatorDevice::mark_writes(const raster::CommandBatch& batch) {
    if (written_lo_.empty()) return;  // a small target: cleared in full
    const int width = target_->width();
    const int height = target_->height();
    // Rows y0..y1 (within the target) widen their spans to [x0, x1] clamped to the target: the
    // clamp once per box, the rows a tight loop (it was out of line per row: 3-8% of a frame).
    const auto row_mark = [this, width](int y0, int y1, int x0, int x1) {
        const int lo = std::max(x0, 0), hi = std::min(x1, width - 1);
        int* const wl = written_lo_.data();
        int* const wh = written_hi_.data();
        for (int y = y0; y <= y1; ++y) {
            wl[y] = std::min(wl[y], lo);
            wh[y] = std::max(wh[y], hi);
        }
    };
    for (const raster::Command& c : batch.commands()) {
        if (c.kind != raster::Command::Kind::Draw || !c.state.depth_write) continue;
        // A viewport other than the whole target: its transform is not the one above.
        const bool whole = !c.state.viewport ||
                           (c.state.viewport->x == 0 && c.state.viewport->y == 0 &&
                            c.state.viewport->width == width && c.state.viewport->height == height);
        const bool ok = whole && (c.double_input
                                      ? mark_draw(c.mesh_d.vertices, c.mesh_d.indices, width, height, row_mark)
                                      : mark_draw(c.mesh.vertices, c.mesh.indices, width, height, row_mark));
        if (!ok) return mark_all();
    }
}

Result<raster::QueryResults> EmulatorDevice::execute(const raster::CommandBatch& batch) {
    if (!target_) return Error{"emulator device: execute before clear (no depth target yet)"};
    raster::ExecuteOptions eo;
    eo.threads = threads_;
    raster::Result<raster::QueryResults> r = raster::execute(*target_, batch, eo);
    // A failed batch was rejected before anything was drawn (raster/raster.h): nothing to mark.
    if (!r) return Error{"emulator device: " + r.error().message};
    mark_writes(batch);
    return std::move(r).value();
}

// Both passes in one rasterization per item (raster/visibility.h), bit-identical to the recorded
// passes (tests/cullide/fused_visibility_test.cpp).
Result<std::vector<std::uint8_t>> EmulatorDevice::visibility_pass(ViewSize size, raster::DepthFormat format,
                                                                  std::span<const raster::VisibilityItem> items) {
    // One per calling thread, shared by every device and frame: a device made per frame (process_frame
    // without a FrameContext) would otherwise fault its buffers in afresh each frame. It keeps no
    // answer from one call to the next, so results cannot depend on what ran before.
    thread_local raster::VisibilityPass pass;
    raster::Result<std::vector<std::uint8_t>> r = pass.run(size.width(), size.height(), format, items, threads_);
    if (!r) return Error{"emulator device: " + r.error().message};
    return std::move(r).value();
}

}  // namespace detail

std::unique_ptr<QueryDevice> make_emulator_device(int threads) {
    return std::make_unique<detail::EmulatorDevice>(threads);
}

}  // namespace cullide

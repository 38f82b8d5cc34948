// osmesa_query_device.cpp: see osmesa_query_device.h.
#include "osmesa_query_device.h"

#include <string>

#include "osmesa_device.h"

namespace cullide_oracle {
namespace {

class OsmesaQueryDevice final : public cullide::QueryDevice {
   public:
    cullide::Status clear(int width, int height, raster::DepthFormat format) override {
        if (!gl_ || gl_->width() != width || gl_->height() != height || format != format_) {
            raster::Result<std::unique_ptr<OsmesaDevice>> d = OsmesaDevice::create(width, height, format);
            if (!d) return cullide::Error{"osmesa device: " + d.error().message};
            gl_ = std::move(d).value();
            format_ = format;
        }
        gl_->clear(1.0);
        return {};
    }

    cullide::Result<raster::QueryResults> execute(const raster::CommandBatch& batch) override {
        if (!gl_) return cullide::Error{"osmesa device: execute before clear (no framebuffer yet)"};
        const auto& commands = batch.commands();
        for (std::size_t i = 0; i < commands.size(); ++i) {
            if (commands[i].kind == raster::Command::Kind::Draw &&
                (commands[i].state.mode != raster::RasterMode::GLExact || commands[i].double_input))
                return cullide::Error{"osmesa device: command " + std::to_string(i) +
                                      " uses the exact-bounds mode or double input, which real GL does not have"};
        }
        if (batch.target_width() != gl_->width() || batch.target_height() != gl_->height())
            return cullide::Error{"osmesa device: batch built for another target size"};
        raster::Result<raster::QueryResults> r = gl_->run(batch);
        if (!r) return cullide::Error{"osmesa device: " + r.error().message};
        return std::move(r).value();
    }

    std::string name() const override { return gl_ ? "osmesa (" + gl_->renderer() + ")" : "osmesa"; }

   private:
    std::unique_ptr<OsmesaDevice> gl_;
    raster::DepthFormat format_ = raster::DepthFormat::D24;
};

}  // namespace

cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_osmesa_query_device() {
    return std::unique_ptr<cullide::QueryDevice>(std::make_unique<OsmesaQueryDevice>());
}

}  // namespace cullide_oracle

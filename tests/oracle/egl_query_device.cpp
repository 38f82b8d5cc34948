// egl_query_device.cpp: see egl_query_device.h.
#include "egl_query_device.h"

#include "egl_device.h"
#include "oracle_query_device.h"

namespace cullide_oracle {

cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_egl_query_device(const std::string& device) {
    return std::unique_ptr<cullide::QueryDevice>(std::make_unique<OracleQueryDevice<EglDevice>>(
        "egl", "real GL", [device](int w, int h, raster::DepthFormat f) { return EglDevice::create(w, h, f, device); }));
}

}  // namespace cullide_oracle

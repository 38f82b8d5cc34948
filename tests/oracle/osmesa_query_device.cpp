// osmesa_query_device.cpp: see osmesa_query_device.h.
#include "osmesa_query_device.h"

#include "oracle_query_device.h"
#include "osmesa_device.h"

namespace cullide_oracle {

cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_osmesa_query_device() {
    return std::unique_ptr<cullide::QueryDevice>(std::make_unique<OracleQueryDevice<OsmesaDevice>>(
        "osmesa", "real GL", [](int w, int h, raster::DepthFormat f) { return OsmesaDevice::create(w, h, f); }));
}

}  // namespace cullide_oracle

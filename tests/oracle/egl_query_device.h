// egl_query_device.h: a cullide::QueryDevice on any GL driver through EGL (egl_device.h), so the
// CULLIDE pipeline's very same pass sequence runs on, say, NVIDIA's GL. Tests and reports only.
#pragma once

#include <memory>
#include <string>

#include "cullide/query_device.h"

namespace cullide_oracle {

// `device` picks the driver as EglDevice::create does (empty: the first that works). The GL rules'
// batches only. See oracle_query_device.h.
[[nodiscard]] cullide::Result<std::unique_ptr<cullide::QueryDevice>> make_egl_query_device(
    const std::string& device = {});

}  // namespace cullide_oracle

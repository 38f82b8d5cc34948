// visibility.cpp: the view size check and the stage names shared by the visibility methods
// (cullide/visibility.h).
#include "cullide/visibility.h"

#include <string>

namespace cullide {

Result<ViewSize> view_size(int requested, VisibilityMode mode) {
    const int pixels = requested == 0 ? default_resolution(mode) : requested;
    if (pixels < kMinViewResolution || pixels > kMaxViewResolution)
        return Error{"resolution must be in " + std::to_string(kMinViewResolution) + ".." +
                     std::to_string(kMaxViewResolution) + " (got " + std::to_string(requested) + ")"};
    return ViewSize(pixels);
}

const char* to_string(CullStage s) {
    switch (s) {
        case CullStage::Boxes:
            return "boxes";
        case CullStage::Objects:
            return "objects";
        case CullStage::SubObjects:
            return "subobjects";
    }
    return "?";
}

}  // namespace cullide

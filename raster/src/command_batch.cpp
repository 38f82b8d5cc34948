// command_batch.cpp: recording and up-front validation of a command batch.
#include "raster/command_batch.h"

#include <cmath>
#include <string>

#include "validate.h"

namespace raster {

void CommandBatch::draw(MeshView mesh, const DrawState& state) {
    Command c;
    c.kind = Command::Kind::Draw;
    c.mesh = mesh;
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

namespace detail {

namespace {
bool finite4(const Float4& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z) && std::isfinite(v.w);
}
std::string cmd_name(std::size_t i) { return "command " + std::to_string(i); }
}  // namespace

Status validate(const DepthTarget& target, const CommandBatch& batch) {
    if (batch.target_width() != target.width() || batch.target_height() != target.height()) {
        return Error{"batch was built for a " + std::to_string(batch.target_width()) + "x" +
                     std::to_string(batch.target_height()) + " target but the target is " +
                     std::to_string(target.width()) + "x" + std::to_string(target.height())};
    }
    bool active = false;
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
                if (s.mode != RasterMode::GLExact) return Error{cmd_name(i) + ": unsupported raster mode"};
                if (static_cast<unsigned>(s.depth_func) > static_cast<unsigned>(DepthFunc::Always))
                    return Error{cmd_name(i) + ": invalid depth function"};
                if (static_cast<unsigned>(s.cull_face) > static_cast<unsigned>(CullFace::Back) ||
                    static_cast<unsigned>(s.front_face) > static_cast<unsigned>(FrontFace::CW))
                    return Error{cmd_name(i) + ": invalid cull/front face"};
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
                const auto& idx = c.mesh.indices;
                const auto& vtx = c.mesh.vertices;
                if (idx.size() % 3 != 0) {
                    return Error{cmd_name(i) + ": index count " + std::to_string(idx.size()) + " is not a multiple of 3"};
                }
                // Only vertices that triangles use are checked (a shared vertex list may hold others).
                for (std::size_t k = 0; k < idx.size(); ++k) {
                    if (idx[k] >= vtx.size()) {
                        return Error{cmd_name(i) + ": index " + std::to_string(idx[k]) + " at position " +
                                     std::to_string(k) + " is beyond the vertex list (size " +
                                     std::to_string(vtx.size()) + ")"};
                    }
                    const Float4& v = vtx[idx[k]];
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

}  // namespace detail
}  // namespace raster

// Fuzz target for cullide/mesh_io.h.
//
// Input: the first byte selects the format (byte % 3: 0 OBJ, 1 PLY, 2 STL; the seeds use the digits
// '0', '1', '2'), the rest is the file. Property checked on every input:
//   - parse_mesh either fails with a non-empty message that starts with the source name, or
//   - returns at least one mesh, every mesh passes validate_mesh, and write_obj followed by
//     parse_mesh gives back the same number of meshes with bit-identical positions and identical
//     triangles (a file with one object keeps its whole vertex list; objects of a multi-object OBJ
//     already hold only referenced vertices, which the reader keeps in order).
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "cullide/mesh_io.h"

namespace {

[[noreturn]] void violated(const char* what, const std::string& detail) {
    std::fprintf(stderr, "mesh_io_fuzz property violated: %s: %s\n", what, detail.c_str());
    std::abort();
}

bool same_bits(double a, double b) {
    return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    static constexpr cullide::MeshFormat kFormats[] = {cullide::MeshFormat::Obj, cullide::MeshFormat::Ply,
                                                       cullide::MeshFormat::Stl};
    const cullide::MeshFormat format = kFormats[data[0] % 3];
    const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
    const std::string source = "<fuzz>";

    cullide::Result<std::vector<cullide::Mesh>> parsed = cullide::parse_mesh(bytes, format, source);
    if (!parsed) {
        const std::string& m = parsed.error().message;
        if (m.size() <= source.size() || m.compare(0, source.size(), source) != 0) {
            violated("error message does not start with the source", m);
        }
        return 0;
    }
    const std::vector<cullide::Mesh>& meshes = parsed.value();
    if (meshes.empty()) violated("success without meshes", "");
    for (const cullide::Mesh& m : meshes) {
        if (cullide::Status s = cullide::validate_mesh(m); !s) violated("invalid mesh", s.error().message);
    }

    const std::string text = cullide::write_obj(meshes);
    cullide::Result<std::vector<cullide::Mesh>> again =
        cullide::parse_mesh(text, cullide::MeshFormat::Obj, "<rt>");
    if (!again) violated("write_obj output does not parse", again.error().message);
    const std::vector<cullide::Mesh>& back = again.value();
    if (back.size() != meshes.size())
        violated("round trip changed the object count", std::to_string(back.size()));
    for (std::size_t k = 0; k < meshes.size(); ++k) {
        const cullide::Mesh& a = meshes[k];
        const cullide::Mesh& b = back[k];
        if (a.positions.size() != b.positions.size()) violated("round trip changed a vertex count", a.name);
        for (std::size_t i = 0; i < a.positions.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
                if (!same_bits(a.positions[i][c], b.positions[i][c]))
                    violated("round trip changed a coordinate", a.name);
            }
        }
        if (a.triangles != b.triangles) violated("round trip changed the triangles", a.name);
    }
    return 0;
}

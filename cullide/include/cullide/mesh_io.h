// cullide/mesh_io.h: reading meshes from OBJ, PLY and STL.
//
// Strict readers: a file either loads completely or fails with a message naming the file, the line
// (text formats) or the element (binary formats) and what is wrong; nothing partial is returned.
// Only positions and faces are kept. Polygons are fan-triangulated (v0 v1 v2, v0 v2 v3, ...) in file
// order. Positions are parsed to the nearest double (std::from_chars) and kept as read.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

enum class MeshFormat { Obj, Ply, Stl };

// What a reader read and dropped, so a caller can tell a plain mesh file from one that carried
// texture coordinates, materials or lines cullide does not keep (the meshes alone cannot say).
// Only OBJ has statements to skip; for PLY and STL every count is zero (their dropped properties are
// declared in the header or fixed by the format, not statements).
struct MeshReadInfo {
    MeshFormat format = MeshFormat::Obj;
    // OBJ statements skipped, by keyword. `count_line` is 1 when the file began with the bare
    // "<vertices> <faces>" line of FCL's test meshes (checked against the file, then dropped).
    struct ObjSkipped {
        std::uint64_t vt = 0, vn = 0, vp = 0, l = 0, p = 0, s = 0, usemtl = 0, mtllib = 0, count_line = 0;
        friend bool operator==(const ObjSkipped&, const ObjSkipped&) = default;
    } obj_skipped;

    // The counts as (keyword, count) in a fixed order (vt vn vp l p s usemtl mtllib count_line), for
    // printing: the CLI's --json writes them under these names.
    [[nodiscard]] std::array<std::pair<std::string_view, std::uint64_t>, 9> skipped() const {
        const ObjSkipped& k = obj_skipped;
        return {{{"vt", k.vt},
                 {"vn", k.vn},
                 {"vp", k.vp},
                 {"l", k.l},
                 {"p", k.p},
                 {"s", k.s},
                 {"usemtl", k.usemtl},
                 {"mtllib", k.mtllib},
                 {"count_line", k.count_line}}};
    }
};

// Reads a file; the format comes from the extension (.obj, .ply, .stl, any case). An OBJ file with
// `o`/`g` groups gives one Mesh per non-empty group, in file order; other formats give one Mesh.
// Mesh::name is the file's stem, or "stem/group" for OBJ groups. When `info` is given it receives
// what the reader skipped; it is written only on success (a failed call changes nothing).
[[nodiscard]] Result<std::vector<Mesh>> read_mesh_file(const std::string& path, MeshReadInfo* info = nullptr);

// The format named by a path's extension (.obj, .ply, .stl, any case), or an error naming the path.
[[nodiscard]] Result<MeshFormat> mesh_format_from_path(const std::string& path);

// Parses bytes already in memory. `source` names them in messages (a path, or "<fuzz>"). `info`: as
// for read_mesh_file.
[[nodiscard]] Result<std::vector<Mesh>> parse_mesh(std::string_view bytes, MeshFormat format,
                                                   const std::string& source, MeshReadInfo* info = nullptr);

// Writers, used by tests (round trips) and by the CLI to export scene frames.
[[nodiscard]] std::string write_obj(const std::vector<Mesh>& objects);  // one `o` group per mesh

}  // namespace cullide

// cullide/mesh_io.h: reading meshes from OBJ, PLY and STL.
//
// Strict readers: a file either loads completely or fails with a message naming the file, the line
// (text formats) or the element (binary formats) and what is wrong; nothing partial is returned.
// Only positions and faces are kept. Polygons are fan-triangulated (v0 v1 v2, v0 v2 v3, ...) in file
// order. Positions are parsed to the nearest double (std::from_chars) and kept as read.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/result.h"

namespace cullide {

enum class MeshFormat { Obj, Ply, Stl };

// Reads a file; the format comes from the extension (.obj, .ply, .stl, any case). An OBJ file with
// `o`/`g` groups gives one Mesh per non-empty group, in file order; other formats give one Mesh.
// Mesh::name is the file's stem, or "stem/group" for OBJ groups.
[[nodiscard]] Result<std::vector<Mesh>> read_mesh_file(const std::string& path);

// The format named by a path's extension (.obj, .ply, .stl, any case), or an error naming the path.
[[nodiscard]] Result<MeshFormat> mesh_format_from_path(const std::string& path);

// Parses bytes already in memory. `source` names them in messages (a path, or "<fuzz>").
[[nodiscard]] Result<std::vector<Mesh>> parse_mesh(std::string_view bytes, MeshFormat format,
                                                   const std::string& source);

// Writers, used by tests (round trips) and by the CLI to export scene frames.
[[nodiscard]] std::string write_obj(const std::vector<Mesh>& objects);  // one `o` group per mesh

}  // namespace cullide

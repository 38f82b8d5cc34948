// mesh_io_detail.h: pieces shared by the OBJ, PLY and STL readers (private to cullide_lib).
//
// Every reader gets the whole file as bytes, builds its meshes in local storage and returns them only
// when the whole file has been read: an error never leaves anything partial behind.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "cullide/mesh.h"
#include "cullide/mesh_io.h"
#include "cullide/result.h"

namespace cullide::mesh_io_detail {

// Largest vertex count a Mesh can index (Tri holds uint32 indices).
inline constexpr std::uint64_t kMaxVertices = 0xFFFFFFFFull;

// The three readers. `source` prefixes every message; `stem` names the meshes.
// parse_obj fills `skipped` (always given) only on success.
[[nodiscard]] Result<std::vector<Mesh>> parse_obj(std::string_view bytes, const std::string& source,
                                                  const std::string& stem, MeshReadInfo::ObjSkipped& skipped);
[[nodiscard]] Result<std::vector<Mesh>> parse_ply(std::string_view bytes, const std::string& source,
                                                  const std::string& stem);
[[nodiscard]] Result<std::vector<Mesh>> parse_stl(std::string_view bytes, const std::string& source,
                                                  const std::string& stem);

// Text helpers. Whitespace is space, tab, CR, VT and FF (a lone CR inside a line is whitespace, so
// CRLF files need no special case beyond the line split).
[[nodiscard]] constexpr bool is_space(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
[[nodiscard]] std::string_view trim(std::string_view s);
// Splits on whitespace into `out` (cleared first).
void split_words(std::string_view s, std::vector<std::string_view>& out);

enum class NumberStatus { Ok, Syntax, OutOfRange, NonFinite };

// One whole token as a double, rounded to nearest (std::from_chars, general format). A single leading
// '+' is accepted (strtod accepts it and exporters emit it). "nan"/"inf" parse but report NonFinite
// (the value is still stored, for callers that ignore a field). Hexadecimal floats are a syntax error.
[[nodiscard]] NumberStatus parse_real(std::string_view token, double& out);
// One whole token as a decimal integer (optional leading '-' or '+').
[[nodiscard]] NumberStatus parse_integer(std::string_view token, std::int64_t& out);
[[nodiscard]] NumberStatus parse_unsigned(std::string_view token, std::uint64_t& out);

// A token as it should appear inside quotes in a message: non-printable bytes escaped as \xNN and long
// tokens cut at 40 characters with "...", so a binary file fed to a text reader gives a readable error.
[[nodiscard]] std::string quote(std::string_view token);

// The message for a bad real number token, e.g. "'1e999' is out of the range of double".
[[nodiscard]] std::string real_number_problem(std::string_view token, NumberStatus status);

}  // namespace cullide::mesh_io_detail

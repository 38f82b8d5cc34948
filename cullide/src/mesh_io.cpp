// mesh_io.cpp: format dispatch, file reading, the OBJ writer and the text helpers the readers share.
// The readers themselves are in mesh_io_obj.cpp, mesh_io_ply.cpp and mesh_io_stl.cpp.
#include "cullide/mesh_io.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <system_error>

#include "mesh_io_detail.h"

namespace cullide {
namespace mesh_io_detail {

std::string_view trim(std::string_view s) {
    std::size_t b = 0;
    while (b < s.size() && is_space(s[b])) ++b;
    std::size_t e = s.size();
    while (e > b && is_space(s[e - 1])) --e;
    return s.substr(b, e - b);
}

void split_words(std::string_view s, std::vector<std::string_view>& out) {
    out.clear();
    std::size_t i = 0;
    while (i < s.size()) {
        while (i < s.size() && is_space(s[i])) ++i;
        const std::size_t start = i;
        while (i < s.size() && !is_space(s[i])) ++i;
        if (i > start) out.push_back(s.substr(start, i - start));
    }
}

namespace {

// The whole token is one number for std::from_chars: one leading '+' is accepted (from_chars rejects
// it) when a digit or point follows, anything left over is a syntax error.
template <class T, class... Format>
NumberStatus parse_token(std::string_view token, T& out, Format... format) {
    if (!token.empty() && token.front() == '+') {
        token.remove_prefix(1);
        if (!token.empty() && (token.front() == '+' || token.front() == '-')) return NumberStatus::Syntax;
    }
    if (token.empty()) return NumberStatus::Syntax;
    T value{};
    const char* end = token.data() + token.size();
    const auto [ptr, ec] = std::from_chars(token.data(), end, value, format...);
    if (ec == std::errc::result_out_of_range) return NumberStatus::OutOfRange;
    if (ec != std::errc{} || ptr != end) return NumberStatus::Syntax;
    out = value;
    return NumberStatus::Ok;
}

}  // namespace

NumberStatus parse_real(std::string_view token, double& out) {
    const NumberStatus s = parse_token(token, out, std::chars_format::general);
    if (s != NumberStatus::Ok) return s;
    return std::isfinite(out) ? NumberStatus::Ok : NumberStatus::NonFinite;
}

NumberStatus parse_integer(std::string_view token, std::int64_t& out) { return parse_token(token, out); }

// from_chars for an unsigned type already refuses a '-'.
NumberStatus parse_unsigned(std::string_view token, std::uint64_t& out) { return parse_token(token, out); }

std::string quote(std::string_view token) {
    constexpr std::size_t kMaxShown = 40;
    std::string out = "'";
    const std::size_t shown = token.size() > kMaxShown ? kMaxShown : token.size();
    for (std::size_t i = 0; i < shown; ++i) {
        const auto c = static_cast<unsigned char>(token[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += static_cast<char>(c);
        } else {
            std::array<char, 8> buf{};
            std::snprintf(buf.data(), buf.size(), "\\x%02x", static_cast<unsigned>(c));
            out += buf.data();
        }
    }
    if (shown < token.size()) out += "...";
    out += "'";
    return out;
}

std::string real_number_problem(std::string_view token, NumberStatus status) {
    switch (status) {
        case NumberStatus::OutOfRange:
            return quote(token) + " is out of the range of double";
        case NumberStatus::NonFinite:
            return quote(token) + " is not a finite number";
        default:
            return quote(token) + " is not a number";
    }
}

}  // namespace mesh_io_detail

namespace {

std::string stem_of(const std::string& source) { return std::filesystem::path(source).stem().string(); }

}  // namespace

Result<std::vector<Mesh>> parse_mesh(std::string_view bytes, MeshFormat format, const std::string& source,
                                     MeshReadInfo* info) {
    const std::string stem = stem_of(source);
    MeshReadInfo read;
    read.format = format;
    Result<std::vector<Mesh>> meshes = Error{source + ": unknown mesh format"};
    switch (format) {
        case MeshFormat::Obj:
            meshes = mesh_io_detail::parse_obj(bytes, source, stem, read.obj_skipped);
            break;
        case MeshFormat::Ply:
            meshes = mesh_io_detail::parse_ply(bytes, source, stem);
            break;
        case MeshFormat::Stl:
            meshes = mesh_io_detail::parse_stl(bytes, source, stem);
            break;
    }
    if (meshes && info != nullptr) *info = read;
    return meshes;
}

Result<MeshFormat> mesh_format_from_path(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) {
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    }
    if (ext == ".obj") return MeshFormat::Obj;
    if (ext == ".ply") return MeshFormat::Ply;
    if (ext == ".stl") return MeshFormat::Stl;
    return Error{path + ": unknown mesh file extension " + mesh_io_detail::quote(ext) +
                 " (expected .obj, .ply or .stl)"};
}

Result<std::vector<Mesh>> read_mesh_file(const std::string& path, MeshReadInfo* info) {
    Result<MeshFormat> format = mesh_format_from_path(path);
    if (!format) return format.error();
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) {
        return Error{path + ": cannot open (no such file, or not a regular file)"};
    }
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (file == nullptr) return Error{path + ": cannot open for reading"};
    std::string bytes;
    std::array<char, 1 << 16> chunk{};
    std::size_t got = 0;
    while ((got = std::fread(chunk.data(), 1, chunk.size(), file)) > 0) bytes.append(chunk.data(), got);
    const bool failed = std::ferror(file) != 0;
    std::fclose(file);
    if (failed) return Error{path + ": read error"};
    return parse_mesh(bytes, format.value(), path, info);
}

namespace {

// Shortest text that parses back to exactly `v` (std::to_chars without a precision is round-trip).
void append_real(std::string& out, double v) {
    std::array<char, 32> buf{};
    const auto [ptr, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    (void)ec;  // 32 bytes always hold the shortest form of a double (at most 24 characters)
    out.append(buf.data(), ptr);
}

void append_index(std::string& out, std::uint64_t v) {
    std::array<char, 24> buf{};
    const auto [ptr, ec] = std::to_chars(buf.data(), buf.data() + buf.size(), v);
    (void)ec;
    out.append(buf.data(), ptr);
}

// An `o` name must stay one token-free-of-surprises line: whitespace, '#' (comment) and '\'
// (continuation) and control bytes become '_'. Names are made unique because the reader merges
// groups that share a name.
std::string object_name(const std::string& name, std::size_t index, std::set<std::string>& used) {
    std::string base;
    for (char c : name) {
        const auto u = static_cast<unsigned char>(c);
        base += (u <= 0x20 || u == 0x7f || c == '#' || c == '\\') ? '_' : c;
    }
    if (base.empty()) base = "object" + std::to_string(index);
    std::string candidate = base;
    for (std::size_t k = 2; used.count(candidate) != 0; ++k) candidate = base + "~" + std::to_string(k);
    used.insert(candidate);
    return candidate;
}

}  // namespace

std::string write_obj(const std::vector<Mesh>& objects) {
    std::string out = "# cullide mesh export: positions in shortest round-trip form\n";
    std::set<std::string> used;
    std::uint64_t base = 1;  // OBJ indices are global and start at 1
    for (std::size_t i = 0; i < objects.size(); ++i) {
        const Mesh& m = objects[i];
        out += "o ";
        out += object_name(m.name, i, used);
        out += '\n';
        for (const Vec3& p : m.positions) {
            out += "v ";
            append_real(out, p.x);
            out += ' ';
            append_real(out, p.y);
            out += ' ';
            append_real(out, p.z);
            out += '\n';
        }
        for (const Tri& t : m.triangles) {
            out += 'f';
            for (std::uint32_t v : t) {
                out += ' ';
                append_index(out, base + v);
            }
            out += '\n';
        }
        base += m.positions.size();
    }
    return out;
}

}  // namespace cullide

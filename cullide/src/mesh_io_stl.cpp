// mesh_io_stl.cpp: a strict STL reader, ASCII and binary.
//
// STL stores each facet's three corners by value: the mesh keeps 3 vertices per facet in file order
// (vertex 3i+k is corner k of facet i) and never welds equal positions, so the reader invents no
// topology. Facet normals and the binary attribute word are read and dropped.
//
// Binary or ASCII: a binary file is 80 header bytes, a little-endian uint32 facet count n, then 50
// bytes per facet, so its size is exactly 84 + 50 n. That size test decides, not the leading "solid"
// (many binary exporters start their header with "solid").
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "mesh_io_detail.h"

namespace cullide::mesh_io_detail {
namespace {

std::uint32_t load_u32_le(const char* p) {
    const auto* b = reinterpret_cast<const unsigned char*>(p);
    return static_cast<std::uint32_t>(b[0]) | (static_cast<std::uint32_t>(b[1]) << 8) |
           (static_cast<std::uint32_t>(b[2]) << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
}

bool binary_size_matches(std::string_view bytes) {
    if (bytes.size() < 84) return false;
    const std::uint64_t n = load_u32_le(bytes.data() + 80);
    return bytes.size() == 84 + 50 * n;
}

Result<std::vector<Mesh>> parse_binary(std::string_view bytes, const std::string& source,
                                       const std::string& stem) {
    const std::uint64_t n = load_u32_le(bytes.data() + 80);
    if (n == 0) return Error{source + ": no triangles (binary STL with 0 facets)"};
    if (3 * n > kMaxVertices) return Error{source + ": too many facets (" + std::to_string(n) + ")"};
    Mesh mesh;
    mesh.name = stem;
    mesh.positions.reserve(3 * n);
    mesh.triangles.reserve(n);
    static constexpr char kAxis[] = {'x', 'y', 'z'};
    for (std::uint64_t i = 0; i < n; ++i) {
        const char* facet = bytes.data() + 84 + 50 * i;
        for (int c = 0; c < 3; ++c) {
            Vec3 p;
            for (int k = 0; k < 3; ++k) {
                // float -> double is exact.
                const auto f = std::bit_cast<float>(load_u32_le(facet + 12 + 12 * c + 4 * k));
                if (!std::isfinite(f)) {
                    return Error{source + ": facet " + std::to_string(i) + ": corner " + std::to_string(c) +
                                 " " + kAxis[k] + " is not finite"};
                }
                p[k] = static_cast<double>(f);
            }
            mesh.positions.push_back(p);
        }
        const auto v = static_cast<std::uint32_t>(3 * i);
        mesh.triangles.push_back({v, v + 1, v + 2});
    }
    std::vector<Mesh> out;
    out.push_back(std::move(mesh));
    return out;
}

// Token stream over the ASCII form with line numbers.
class Tokens {
 public:
    explicit Tokens(std::string_view bytes) : bytes_(bytes) {}
    // False at the end of the input.
    bool next(std::string_view& token) {
        while (pos_ < bytes_.size() && (is_space(bytes_[pos_]) || bytes_[pos_] == '\n')) {
            if (bytes_[pos_] == '\n') ++line_;
            ++pos_;
        }
        if (pos_ >= bytes_.size()) return false;
        const std::size_t start = pos_;
        while (pos_ < bytes_.size() && !is_space(bytes_[pos_]) && bytes_[pos_] != '\n') ++pos_;
        token = bytes_.substr(start, pos_ - start);
        token_line_ = line_;
        return true;
    }
    // The rest of the current line (for the free-text names after solid / endsolid).
    void skip_line() {
        while (pos_ < bytes_.size() && bytes_[pos_] != '\n') ++pos_;
    }
    [[nodiscard]] std::size_t line() const { return token_line_; }
    [[nodiscard]] std::size_t current_line() const { return line_; }

 private:
    std::string_view bytes_;
    std::size_t pos_ = 0;
    std::size_t line_ = 1;
    std::size_t token_line_ = 1;
};

Result<std::vector<Mesh>> parse_ascii(std::string_view bytes, const std::string& source,
                                      const std::string& stem) {
    Tokens tokens(bytes);
    Mesh mesh;
    mesh.name = stem;
    std::string_view tok;
    auto at = [&](std::size_t line, const std::string& what) {
        return Error{source + ":" + std::to_string(line) + ": " + what};
    };
    // Reads one token and requires it to be `word`.
    auto expect = [&](std::string_view word, std::string& problem) {
        if (!tokens.next(tok)) {
            problem = source + ":" + std::to_string(tokens.current_line()) + ": file ends where '" +
                      std::string(word) + "' was expected";
            return false;
        }
        if (tok != word) {
            problem = source + ":" + std::to_string(tokens.line()) + ": expected '" + std::string(word) +
                      "', found " + quote(tok);
            return false;
        }
        return true;
    };
    // Reads three numbers; `finite` requires finite values (normals are only checked to be numbers).
    auto numbers = [&](double(&v)[3], bool finite, std::string& problem) {
        for (double& x : v) {
            if (!tokens.next(tok)) {
                problem = source + ":" + std::to_string(tokens.current_line()) +
                          ": file ends inside a number triple";
                return false;
            }
            const NumberStatus st = parse_real(tok, x);
            if (st == NumberStatus::Ok || (st == NumberStatus::NonFinite && !finite)) continue;
            problem = source + ":" + std::to_string(tokens.line()) + ": " + real_number_problem(tok, st);
            return false;
        }
        return true;
    };

    std::string problem;
    if (!tokens.next(tok) || tok != "solid") return at(tokens.line(), "ASCII STL must start with 'solid'");
    tokens.skip_line();
    bool in_solid = true;
    while (tokens.next(tok)) {
        if (!in_solid) {
            // Several solids in one file are read into the one mesh, in file order.
            if (tok != "solid")
                return at(tokens.line(), "expected 'solid' or the end of the file, found " + quote(tok));
            tokens.skip_line();
            in_solid = true;
            continue;
        }
        if (tok == "endsolid") {
            tokens.skip_line();
            in_solid = false;
            continue;
        }
        if (tok != "facet") return at(tokens.line(), "expected 'facet' or 'endsolid', found " + quote(tok));
        double normal[3];
        if (!expect("normal", problem) || !numbers(normal, false, problem) || !expect("outer", problem) ||
            !expect("loop", problem)) {
            return Error{problem};
        }
        for (int c = 0; c < 3; ++c) {
            double p[3];
            if (!tokens.next(tok)) return at(tokens.current_line(), "file ends inside a facet");
            if (tok != "vertex") {
                if (tok == "endloop")
                    return at(tokens.line(),
                              "facet has " + std::to_string(c) + " vertices (needs exactly 3)");
                return at(tokens.line(), "expected 'vertex', found " + quote(tok));
            }
            if (!numbers(p, true, problem)) return Error{problem};
            if (mesh.positions.size() >= kMaxVertices) return at(tokens.line(), "too many vertices");
            mesh.positions.push_back({p[0], p[1], p[2]});
        }
        if (!tokens.next(tok)) return at(tokens.current_line(), "file ends inside a facet");
        if (tok == "vertex") return at(tokens.line(), "facet has more than 3 vertices (needs exactly 3)");
        if (tok != "endloop") return at(tokens.line(), "expected 'endloop', found " + quote(tok));
        if (!expect("endfacet", problem)) return Error{problem};
        const auto v = static_cast<std::uint32_t>(mesh.positions.size() - 3);
        mesh.triangles.push_back({v, v + 1, v + 2});
    }
    if (in_solid) return at(tokens.current_line(), "file ends before 'endsolid'");
    if (mesh.triangles.empty()) return Error{source + ": no triangles (the file has no facets)"};
    std::vector<Mesh> out;
    out.push_back(std::move(mesh));
    return out;
}

}  // namespace

Result<std::vector<Mesh>> parse_stl(std::string_view bytes, const std::string& source,
                                    const std::string& stem) {
    if (binary_size_matches(bytes)) return parse_binary(bytes, source, stem);
    // Not a well-sized binary file: it must be ASCII, which starts with "solid" (after optional blanks).
    std::size_t i = 0;
    while (i < bytes.size() && (is_space(bytes[i]) || bytes[i] == '\n')) ++i;
    const bool solid = bytes.substr(i, 5) == "solid";
    // A binary file whose header starts with "solid" but whose size is wrong (truncated, or extra
    // bytes) would otherwise get a puzzling ASCII syntax error: text STL never holds a NUL byte.
    const bool has_nul = bytes.find('\0') != std::string_view::npos;
    if (solid && !has_nul) return parse_ascii(bytes, source, stem);
    const std::string why = solid ? "not ASCII STL (it contains NUL bytes)" : "not ASCII STL (no 'solid')";
    if (bytes.size() >= 84) {
        const std::uint64_t n = load_u32_le(bytes.data() + 80);
        return Error{source + ": " + why + " and not binary STL: " + std::to_string(n) + " facets need " +
                     std::to_string(84 + 50 * n) + " bytes, the file has " + std::to_string(bytes.size())};
    }
    return Error{source + ": " + why + " and too short for binary STL (" + std::to_string(bytes.size()) +
                 " bytes, at least 84 needed)"};
}

}  // namespace cullide::mesh_io_detail

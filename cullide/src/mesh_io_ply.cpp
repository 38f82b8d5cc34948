// mesh_io_ply.cpp: a strict PLY reader (ascii, binary_little_endian, binary_big_endian; version 1.0).
//
// Kept: element `vertex` (scalar properties x, y, z of any type), element `face` (list property
// `vertex_indices` or `vertex_index`; polygons fan-triangulated) and element `tristrips` (one list
// `vertex_indices`: triangle strips separated by -1). Every other property and element is read
// and skipped, list properties included, so a file either parses to the last byte or is rejected.
//
// All PLY scalar types are at most 32-bit integers or floats, so every value is held as a double
// exactly; positions of type float/double convert exactly, ASCII positions are parsed to nearest.
//
// ASCII bodies hold one element instance per line (what every writer produces): a line with too few
// or too many values is an error, which catches wrong counts that a token-stream reader would shift
// silently into the next element. Blank lines in the body are skipped.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "mesh_io_detail.h"

namespace cullide::mesh_io_detail {
namespace {

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

bool ply_type_from_name(std::string_view name, PlyType& type) {
    struct Entry {
        std::string_view name;
        PlyType type;
    };
    static constexpr Entry kTypes[] = {
        {"char", PlyType::Int8},       {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},     {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},   {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},     {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},   {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64},
    };
    for (const Entry& e : kTypes) {
        if (e.name == name) {
            type = e.type;
            return true;
        }
    }
    return false;
}

std::size_t ply_type_size(PlyType t) {
    switch (t) {
        case PlyType::Int8:
        case PlyType::UInt8:
            return 1;
        case PlyType::Int16:
        case PlyType::UInt16:
            return 2;
        case PlyType::Int32:
        case PlyType::UInt32:
        case PlyType::Float32:
            return 4;
        case PlyType::Float64:
            return 8;
    }
    return 8;
}

bool is_integer_type(PlyType t) { return t != PlyType::Float32 && t != PlyType::Float64; }

enum class Role { Skip, X, Y, Z, Indices };

struct PlyProperty {
    std::string name;
    bool is_list = false;
    PlyType count_type = PlyType::UInt8;  // lists only
    PlyType type = PlyType::Float32;
    Role role = Role::Skip;
};

enum class Kind { Other, Vertex, Face, Strips };

struct PlyElement {
    std::string name;
    std::uint64_t count = 0;
    std::vector<PlyProperty> properties;
    Kind kind = Kind::Other;
};

enum class Encoding { Ascii, BinaryLittle, BinaryBig };

// Binary values, bounds-checked. A read past the end reports the file as truncated.
class BinarySource {
 public:
    BinarySource(std::string_view bytes, std::size_t pos, bool big_endian)
        : bytes_(bytes), pos_(pos), big_endian_(big_endian) {}

    bool begin_instance(std::string& /*problem*/) { return true; }
    bool value(PlyType t, double& out, std::string& problem) {
        const std::size_t size = ply_type_size(t);
        if (bytes_.size() - pos_ < size) {
            problem = "the file ends inside the element (truncated)";
            return false;
        }
        std::uint64_t raw = 0;
        for (std::size_t i = 0; i < size; ++i) {
            const auto b = static_cast<unsigned char>(bytes_[pos_ + (big_endian_ ? i : size - 1 - i)]);
            raw = (raw << 8) | b;
        }
        pos_ += size;
        switch (t) {
            case PlyType::Int8:
                out = static_cast<std::int8_t>(static_cast<std::uint8_t>(raw));
                break;
            case PlyType::UInt8:
                out = static_cast<std::uint8_t>(raw);
                break;
            case PlyType::Int16:
                out = static_cast<std::int16_t>(static_cast<std::uint16_t>(raw));
                break;
            case PlyType::UInt16:
                out = static_cast<std::uint16_t>(raw);
                break;
            case PlyType::Int32:
                out = static_cast<std::int32_t>(static_cast<std::uint32_t>(raw));
                break;
            case PlyType::UInt32:
                out = static_cast<std::uint32_t>(raw);
                break;
            case PlyType::Float32:
                out = static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(raw)));
                break;
            case PlyType::Float64:
                out = std::bit_cast<double>(raw);
                break;
        }
        return true;
    }
    bool end_instance(std::string& /*problem*/) { return true; }
    // Called when an element's instances are all read.
    [[nodiscard]] std::string where(const PlyElement& e, std::uint64_t i, const std::string& source) const {
        return source + ": " + e.name + " " + std::to_string(i) + ": ";
    }
    [[nodiscard]] Status finish(const std::string& source) const {
        if (pos_ != bytes_.size()) {
            return Error{source + ": " + std::to_string(bytes_.size() - pos_) +
                         " bytes after the last element (wrong counts in the header?)"};
        }
        return {};
    }

 private:
    std::string_view bytes_;
    std::size_t pos_;
    bool big_endian_;
};

// ASCII values: one element instance per line.
class AsciiSource {
 public:
    AsciiSource(std::string_view bytes, std::size_t pos, std::size_t line)
        : bytes_(bytes), pos_(pos), line_(line) {}

    bool begin_instance(std::string& problem) {
        while (pos_ < bytes_.size()) {
            const std::size_t nl = bytes_.find('\n', pos_);
            const std::size_t end = nl == std::string_view::npos ? bytes_.size() : nl;
            const std::string_view text = bytes_.substr(pos_, end - pos_);
            pos_ = nl == std::string_view::npos ? bytes_.size() : nl + 1;
            ++line_;
            split_words(text, words_);
            if (!words_.empty()) {
                next_ = 0;
                return true;
            }
        }
        problem = "the file ends before this element (fewer elements than the header declares)";
        return false;
    }
    bool value(PlyType t, double& out, std::string& problem) {
        if (next_ >= words_.size()) {
            problem = "the line has too few values";
            return false;
        }
        const std::string_view tok = words_[next_++];
        if (is_integer_type(t)) {
            std::int64_t v = 0;
            if (parse_integer(tok, v) != NumberStatus::Ok || v < type_min(t) || v > type_max(t)) {
                problem = quote(tok) + " is not a value of the property's integer type";
                return false;
            }
            out = static_cast<double>(v);  // |v| < 2^32: exact
            return true;
        }
        const NumberStatus st = parse_real(tok, out);
        if (st == NumberStatus::Ok || st == NumberStatus::NonFinite) return true;  // finiteness: caller
        problem = real_number_problem(tok, st);
        return false;
    }
    bool end_instance(std::string& problem) {
        if (next_ != words_.size()) {
            problem = "the line has " + std::to_string(words_.size() - next_) + " extra value(s)";
            return false;
        }
        return true;
    }
    [[nodiscard]] std::string where(const PlyElement& e, std::uint64_t i, const std::string& source) const {
        return source + ":" + std::to_string(line_) + ": " + e.name + " " + std::to_string(i) + ": ";
    }
    [[nodiscard]] Status finish(const std::string& source) {
        std::string ignored;
        if (begin_instance(ignored)) {
            return Error{source + ":" + std::to_string(line_) +
                         ": data after the last element (wrong counts in the header?)"};
        }
        return {};
    }

 private:
    static std::int64_t type_min(PlyType t) {
        switch (t) {
            case PlyType::Int8:
                return -128;
            case PlyType::Int16:
                return -32768;
            case PlyType::Int32:
                return -2147483648LL;
            default:
                return 0;
        }
    }
    static std::int64_t type_max(PlyType t) {
        switch (t) {
            case PlyType::Int8:
                return 127;
            case PlyType::UInt8:
                return 255;
            case PlyType::Int16:
                return 32767;
            case PlyType::UInt16:
                return 65535;
            case PlyType::Int32:
                return 2147483647LL;
            default:
                return 4294967295LL;
        }
    }

    std::string_view bytes_;
    std::size_t pos_;
    std::size_t line_;
    std::vector<std::string_view> words_;
    std::size_t next_ = 0;
};

struct Header {
    Encoding encoding = Encoding::Ascii;
    std::vector<PlyElement> elements;
    std::size_t body = 0;       // byte offset of the first element
    std::size_t body_line = 0;  // lines before the body (ASCII line numbers continue from here)
    std::uint64_t vertex_count = 0;
};

Result<Header> parse_header(std::string_view bytes, const std::string& source) {
    Header h;
    std::size_t pos = 0;
    std::size_t line_number = 0;
    bool have_format = false;
    bool have_vertex = false;
    std::vector<std::string_view> words;
    auto fail = [&](const std::string& what) {
        return Error{source + ":" + std::to_string(line_number) + ": " + what};
    };
    while (true) {
        if (pos >= bytes.size()) {
            return Error{source + ": the PLY header has no 'end_header' line"};
        }
        const std::size_t nl = bytes.find('\n', pos);
        const std::size_t end = nl == std::string_view::npos ? bytes.size() : nl;
        std::string_view text = bytes.substr(pos, end - pos);
        pos = nl == std::string_view::npos ? bytes.size() : nl + 1;
        ++line_number;
        if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
        if (line_number == 1) {
            if (text != "ply") return fail("not a PLY file (the first line must be 'ply')");
            continue;
        }
        split_words(text, words);
        if (words.empty()) continue;
        const std::string_view key = words[0];
        if (key == "comment" || key == "obj_info") continue;
        if (key == "format") {
            if (have_format) return fail("a second 'format' line");
            if (words.size() != 3) return fail("expected 'format <encoding> 1.0'");
            if (words[1] == "ascii") {
                h.encoding = Encoding::Ascii;
            } else if (words[1] == "binary_little_endian") {
                h.encoding = Encoding::BinaryLittle;
            } else if (words[1] == "binary_big_endian") {
                h.encoding = Encoding::BinaryBig;
            } else {
                return fail("unknown PLY encoding " + quote(words[1]));
            }
            if (words[2] != "1.0")
                return fail("unsupported PLY version " + quote(words[2]) + " (expected 1.0)");
            have_format = true;
        } else if (key == "element") {
            if (!have_format) return fail("'element' before the 'format' line");
            if (words.size() != 3) return fail("expected 'element <name> <count>'");
            PlyElement e;
            e.name = std::string(words[1]);
            for (const PlyElement& other : h.elements) {
                if (other.name == e.name) return fail("element " + quote(e.name) + " is declared twice");
            }
            if (parse_unsigned(words[2], e.count) != NumberStatus::Ok) {
                return fail("element count " + quote(words[2]) + " is not a non-negative integer in range");
            }
            if (e.name == "vertex") {
                e.kind = Kind::Vertex;
                if (e.count > kMaxVertices) {
                    return fail("vertex count " + std::to_string(e.count) + " exceeds the limit " +
                                std::to_string(kMaxVertices));
                }
                h.vertex_count = e.count;
                have_vertex = true;
            } else if (e.name == "face") {
                e.kind = Kind::Face;
            } else if (e.name == "tristrips") {
                e.kind = Kind::Strips;
            }
            h.elements.push_back(std::move(e));
        } else if (key == "property") {
            if (h.elements.empty()) return fail("'property' before any 'element'");
            PlyElement& e = h.elements.back();
            PlyProperty p;
            std::string_view type_name;
            if (words.size() >= 2 && words[1] == "list") {
                if (words.size() != 5)
                    return fail("expected 'property list <count type> <value type> <name>'");
                p.is_list = true;
                if (!ply_type_from_name(words[2], p.count_type))
                    return fail("unknown PLY type " + quote(words[2]));
                if (!is_integer_type(p.count_type))
                    return fail("list count type " + quote(words[2]) + " is not an integer type");
                type_name = words[3];
                p.name = std::string(words[4]);
            } else {
                if (words.size() != 3) return fail("expected 'property <type> <name>'");
                type_name = words[1];
                p.name = std::string(words[2]);
            }
            if (!ply_type_from_name(type_name, p.type)) return fail("unknown PLY type " + quote(type_name));
            for (const PlyProperty& other : e.properties) {
                if (other.name == p.name)
                    return fail("property " + quote(p.name) + " is declared twice in " + quote(e.name));
            }
            if (e.kind == Kind::Vertex && (p.name == "x" || p.name == "y" || p.name == "z")) {
                if (p.is_list)
                    return fail("vertex property " + quote(p.name) + " must be a scalar, not a list");
                p.role = p.name == "x" ? Role::X : (p.name == "y" ? Role::Y : Role::Z);
            }
            if ((e.kind == Kind::Face || e.kind == Kind::Strips) &&
                (p.name == "vertex_indices" || p.name == "vertex_index")) {
                for (const PlyProperty& other : e.properties) {
                    if (other.role == Role::Indices)
                        return fail(quote(e.name) + " has both vertex_indices and vertex_index");
                }
                if (!p.is_list) return fail(quote(e.name) + " property " + quote(p.name) + " must be a list");
                if (!is_integer_type(p.type))
                    return fail("vertex index type " + quote(type_name) + " is not an integer type");
                p.role = Role::Indices;
            }
            e.properties.push_back(std::move(p));
        } else if (key == "end_header") {
            if (words.size() != 1) return fail("unexpected text after 'end_header'");
            break;
        } else {
            return fail("unknown PLY header keyword " + quote(key));
        }
    }
    auto fail_end = [&](const std::string& what) { return Error{source + ": " + what}; };
    if (!have_format) return fail_end("the PLY header has no 'format' line");
    if (!have_vertex) return fail_end("the PLY header declares no 'vertex' element");
    bool have_faces = false;
    for (const PlyElement& e : h.elements) {
        if (e.properties.empty()) return fail_end("element " + quote(e.name) + " declares no properties");
        if (e.kind == Kind::Vertex) {
            for (Role r : {Role::X, Role::Y, Role::Z}) {
                bool found = false;
                for (const PlyProperty& p : e.properties) found = found || p.role == r;
                if (!found) {
                    return fail_end(std::string("element 'vertex' has no property '") +
                                    (r == Role::X ? "x" : (r == Role::Y ? "y" : "z")) + "'");
                }
            }
        }
        if (e.kind == Kind::Face || e.kind == Kind::Strips) {
            bool found = false;
            for (const PlyProperty& p : e.properties) found = found || p.role == Role::Indices;
            if (!found) return fail_end("element " + quote(e.name) + " has no 'vertex_indices' list");
            have_faces = true;
        }
    }
    if (!have_faces)
        return fail_end("no triangles (the PLY header declares no 'face' or 'tristrips' element)");
    h.body = pos;
    h.body_line = line_number;
    return h;
}

// Reads one list count (an integer type, checked non-negative).
template <class Source>
bool read_count(Source& src, PlyType t, std::uint64_t& count, std::string& problem) {
    double c = 0;
    if (!src.value(t, c, problem)) return false;
    if (c < 0) {
        problem = "list count " + std::to_string(static_cast<std::int64_t>(c)) + " is negative";
        return false;
    }
    count = static_cast<std::uint64_t>(c);
    return true;
}

std::string beyond(double index, std::uint64_t size) {
    return "vertex index " + std::to_string(static_cast<std::int64_t>(index)) +
           " is beyond the vertex list (size " + std::to_string(size) + ")";
}

// Triangle strip to triangles with the alternating orientation of GL_TRIANGLE_STRIP: triangle k of a
// strip is (s[k], s[k+1], s[k+2]) for even k and (s[k+1], s[k], s[k+2]) for odd k, so every triangle
// keeps the winding of the first.
bool flush_strip(std::vector<std::uint32_t>& strip, std::vector<Tri>& out, std::string& problem) {
    if (strip.empty()) return true;  // "-1 -1" or a trailing -1: an empty strip has nothing to drop
    if (strip.size() < 3) {
        problem = "a strip of " + std::to_string(strip.size()) + " vertices makes no triangle";
        return false;
    }
    for (std::size_t k = 0; k + 2 < strip.size(); ++k) {
        if (k % 2 == 0) {
            out.push_back({strip[k], strip[k + 1], strip[k + 2]});
        } else {
            out.push_back({strip[k + 1], strip[k], strip[k + 2]});
        }
    }
    strip.clear();
    return true;
}

template <class Source>
Result<std::vector<Mesh>> read_body(Source& src, const Header& h, std::size_t body_bytes,
                                    const std::string& source, const std::string& stem) {
    Mesh mesh;
    mesh.name = stem;
    std::vector<std::uint32_t> polygon;
    std::string problem;
    for (const PlyElement& e : h.elements) {
        // A vertex takes at least 3 bytes in any encoding: never reserve more than the data can hold,
        // whatever count the header claims.
        if (e.kind == Kind::Vertex) {
            mesh.positions.reserve(
                static_cast<std::size_t>(std::min<std::uint64_t>(e.count, body_bytes / 3)));
        }
        for (std::uint64_t i = 0; i < e.count; ++i) {
            auto fail = [&] { return Error{src.where(e, i, source) + problem}; };
            if (!src.begin_instance(problem)) return fail();
            double xyz[3] = {0, 0, 0};
            for (const PlyProperty& p : e.properties) {
                if (!p.is_list) {
                    double v = 0;
                    if (!src.value(p.type, v, problem)) return fail();
                    if (p.role == Role::X || p.role == Role::Y || p.role == Role::Z) {
                        if (!std::isfinite(v)) {
                            problem = "coordinate " + p.name + " is not finite";
                            return fail();
                        }
                        xyz[p.role == Role::X ? 0 : (p.role == Role::Y ? 1 : 2)] = v;
                    }
                    continue;
                }
                std::uint64_t count = 0;
                if (!read_count(src, p.count_type, count, problem)) return fail();
                if (p.role != Role::Indices) {
                    for (std::uint64_t k = 0; k < count; ++k) {
                        double ignored = 0;
                        if (!src.value(p.type, ignored, problem)) return fail();
                    }
                    continue;
                }
                if (e.kind == Kind::Face) {
                    if (count < 3) {
                        problem = "has " + std::to_string(count) + " vertices (needs at least 3)";
                        return fail();
                    }
                    polygon.clear();
                    for (std::uint64_t k = 0; k < count; ++k) {
                        double v = 0;
                        if (!src.value(p.type, v, problem)) return fail();
                        if (v < 0 || v >= static_cast<double>(h.vertex_count)) {
                            problem = beyond(v, h.vertex_count);
                            if (v < 0)
                                problem = "vertex index " + std::to_string(static_cast<std::int64_t>(v)) +
                                          " is negative";
                            return fail();
                        }
                        polygon.push_back(static_cast<std::uint32_t>(v));
                    }
                    for (std::size_t k = 1; k + 1 < polygon.size(); ++k) {
                        mesh.triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
                    }
                } else {  // tristrips: -1 separates strips
                    polygon.clear();
                    for (std::uint64_t k = 0; k < count; ++k) {
                        double v = 0;
                        if (!src.value(p.type, v, problem)) return fail();
                        if (v == -1) {
                            if (!flush_strip(polygon, mesh.triangles, problem)) return fail();
                            continue;
                        }
                        if (v < 0 || v >= static_cast<double>(h.vertex_count)) {
                            problem = beyond(v, h.vertex_count);
                            if (v < 0) {
                                problem = "strip index " + std::to_string(static_cast<std::int64_t>(v)) +
                                          " is negative (only -1, the strip separator, is allowed)";
                            }
                            return fail();
                        }
                        polygon.push_back(static_cast<std::uint32_t>(v));
                    }
                    if (!flush_strip(polygon, mesh.triangles, problem)) return fail();
                }
            }
            if (!src.end_instance(problem)) return fail();
            if (e.kind == Kind::Vertex) mesh.positions.push_back({xyz[0], xyz[1], xyz[2]});
        }
    }
    if (Status s = src.finish(source); !s) return s.error();
    if (mesh.triangles.empty()) return Error{source + ": no triangles (the face elements are empty)"};
    std::vector<Mesh> out;
    out.push_back(std::move(mesh));
    return out;
}

}  // namespace

Result<std::vector<Mesh>> parse_ply(std::string_view bytes, const std::string& source,
                                    const std::string& stem) {
    Result<Header> header = parse_header(bytes, source);
    if (!header) return header.error();
    const Header& h = header.value();
    if (h.encoding == Encoding::Ascii) {
        AsciiSource src(bytes, h.body, h.body_line);
        return read_body(src, h, bytes.size() - h.body, source, stem);
    }
    BinarySource src(bytes, h.body, h.encoding == Encoding::BinaryBig);
    return read_body(src, h, bytes.size() - h.body, source, stem);
}

}  // namespace cullide::mesh_io_detail

// mesh_io_obj.cpp: a strict Wavefront OBJ reader (positions and polygon faces only).
//
// Rules (docs/mesh-input.md has the full list with examples):
// - A logical line is a physical line with its comment ('#' to the end) removed; a logical line whose
//   remaining text ends in '\' continues on the next physical line. Messages name the first physical
//   line of the statement.
// - `v x y z [w]`: positions; w is checked and dropped. `f`: 3 or more vertex references of the forms
//   v, v/vt, v//vn, v/vt/vn; negative references count back from the last vertex read so far, and every
//   reference must name an element already read (no forward references).
// - `o name` / `g name...`: faces that follow belong to the object of that name; statements repeating a
//   name continue the same object; `g`/`o` without a name returns to the ungrouped object. Objects are
//   returned in the order of their first face; a name that never gets a face is not an object.
// - Statements carrying data we do not keep are skipped and counted per keyword (MeshReadInfo): vt vn
//   vp l p s usemtl mtllib (the vt and vn counts also range-check face references to them). Anything
//   else is an error: a lenient reader that skips what it does not understand silently loses geometry
//   (free-form surfaces, a corrupted line), and collision results on a partial mesh are wrong without
//   warning.
// - A first statement of exactly two unsigned integers is the "<vertices> <faces>" count line FCL's
//   test meshes begin with. It is checked against the `v` and `f` statements the file really holds
//   (a file cut short, or a count line that is really something else, must not pass silently), then
//   dropped. Anywhere else such a line is an error.
#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "mesh_io_detail.h"

namespace cullide::mesh_io_detail {
namespace {

struct ObjObject {
    std::string name;
    std::vector<Tri> triangles;  // global (file) vertex indices, 0-based
};

// Produces logical lines: comments stripped, continuations joined, CRLF handled (CR is whitespace).
class LogicalLines {
 public:
    explicit LogicalLines(std::string_view bytes) : bytes_(bytes) {}

    // False at the end of the input. `line` stays valid until the next call.
    bool next(std::string_view& line, std::size_t& line_number) {
        if (pos_ >= bytes_.size()) return false;
        joined_.clear();
        bool continued = false;
        line_number = physical_line_ + 1;
        while (pos_ < bytes_.size()) {
            std::string_view text = physical();
            if (const std::size_t hash = text.find('#'); hash != std::string_view::npos) {
                text = text.substr(0, hash);
            }
            text = trim_right(text);
            const bool continues = !text.empty() && text.back() == '\\';
            if (continues) text.remove_suffix(1);
            if (!continues && !continued) {
                line = text;
                return true;
            }
            joined_.append(text);
            joined_ += ' ';
            continued = true;
            if (!continues) break;
        }
        line = joined_;
        return true;
    }

 private:
    static std::string_view trim_right(std::string_view s) {
        while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
        return s;
    }
    std::string_view physical() {
        const std::size_t nl = bytes_.find('\n', pos_);
        const std::size_t end = nl == std::string_view::npos ? bytes_.size() : nl;
        std::string_view text = bytes_.substr(pos_, end - pos_);
        pos_ = nl == std::string_view::npos ? bytes_.size() : nl + 1;
        ++physical_line_;
        return text;
    }

    std::string_view bytes_;
    std::size_t pos_ = 0;
    std::size_t physical_line_ = 0;
    std::string joined_;
};

// Resolves one OBJ reference (1-based, or negative = relative to the end) against a list of `size`
// elements read so far. Returns the 0-based index or an error text.
bool resolve_reference(std::string_view token, std::uint64_t size, const char* what, const char* list,
                       std::uint64_t& index, std::string& problem) {
    std::int64_t value = 0;
    const NumberStatus st = parse_integer(token, value);
    if (st != NumberStatus::Ok) {
        problem = std::string(what) + " " + quote(token) + " is not an integer in range";
        return false;
    }
    if (value == 0) {
        problem = std::string(what) + " 0 is invalid (OBJ indices start at 1)";
        return false;
    }
    if (value > 0) {
        const auto v = static_cast<std::uint64_t>(value);
        if (v > size) {
            problem = std::string(what) + " " + std::to_string(value) + " is beyond the " + list + " (size " +
                      std::to_string(size) + ")";
            return false;
        }
        index = v - 1;
        return true;
    }
    // -(value + 1) + 1 avoids overflowing on INT64_MIN.
    const std::uint64_t back = static_cast<std::uint64_t>(-(value + 1)) + 1;
    if (back > size) {
        problem = std::string(what) + " " + std::to_string(value) + " reaches before the start of the " +
                  list + " (size " + std::to_string(size) + ")";
        return false;
    }
    index = size - back;
    return true;
}

// The counter of a statement read and dropped, or nullptr when `keyword` is not one of them.
std::uint64_t* skipped_counter(std::string_view keyword, MeshReadInfo::ObjSkipped& skipped) {
    if (keyword == "vt") return &skipped.vt;
    if (keyword == "vn") return &skipped.vn;
    if (keyword == "vp") return &skipped.vp;
    if (keyword == "l") return &skipped.l;
    if (keyword == "p") return &skipped.p;
    if (keyword == "s") return &skipped.s;
    if (keyword == "usemtl") return &skipped.usemtl;
    if (keyword == "mtllib") return &skipped.mtllib;
    return nullptr;
}

// FCL's "<vertices> <faces>" line: exactly two unsigned decimal integers.
bool is_count_line(const std::vector<std::string_view>& words, std::uint64_t& vertices, std::uint64_t& faces) {
    return words.size() == 2 && parse_unsigned(words[0], vertices) == NumberStatus::Ok &&
           parse_unsigned(words[1], faces) == NumberStatus::Ok;
}

std::string count_of(std::uint64_t n, const char* one, const char* many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
}

// Every object keeps only the vertices its faces reference, in increasing file order. `scratch` has
// one entry per file vertex, all kNone on entry and on exit.
Mesh compact(const ObjObject& object, const std::vector<Vec3>& positions,
             std::vector<std::uint32_t>& scratch) {
    constexpr std::uint32_t kNone = 0xFFFFFFFFu;
    std::vector<std::uint32_t> used;
    used.reserve(object.triangles.size() * 3);
    for (const Tri& t : object.triangles) used.insert(used.end(), t.begin(), t.end());
    std::sort(used.begin(), used.end());
    used.erase(std::unique(used.begin(), used.end()), used.end());
    Mesh mesh;
    mesh.name = object.name;
    mesh.positions.reserve(used.size());
    for (std::size_t i = 0; i < used.size(); ++i) {
        scratch[used[i]] = static_cast<std::uint32_t>(i);
        mesh.positions.push_back(positions[used[i]]);
    }
    mesh.triangles.reserve(object.triangles.size());
    for (const Tri& t : object.triangles)
        mesh.triangles.push_back({scratch[t[0]], scratch[t[1]], scratch[t[2]]});
    for (std::uint32_t g : used) scratch[g] = kNone;
    return mesh;
}

}  // namespace

Result<std::vector<Mesh>> parse_obj(std::string_view bytes, const std::string& source,
                                    const std::string& stem, MeshReadInfo::ObjSkipped& skipped_out) {
    std::vector<Vec3> positions;
    MeshReadInfo::ObjSkipped skipped;  // written to skipped_out only on success
    const std::uint64_t& texcoord_count = skipped.vt;
    const std::uint64_t& normal_count = skipped.vn;
    std::uint64_t face_count = 0;  // `f` statements (polygons, before triangulation)
    bool first_statement = true;
    std::uint64_t declared_vertices = 0, declared_faces = 0;
    std::size_t count_line_number = 0;
    std::vector<ObjObject> objects;
    std::map<std::string, std::size_t> object_by_name;  // lookup only; output order is first-face order
    std::string current_name = stem;                    // the ungrouped object is named by the stem alone
    std::size_t current_object = SIZE_MAX;              // index into objects once the name has a face

    std::vector<std::string_view> words;
    std::vector<std::uint32_t> polygon;
    LogicalLines lines(bytes);
    std::string_view line;
    std::size_t line_number = 0;
    auto fail = [&](const std::string& what) {
        return Error{source + ":" + std::to_string(line_number) + ": " + what};
    };

    while (lines.next(line, line_number)) {
        split_words(line, words);
        if (words.empty()) continue;
        const std::string_view keyword = words[0];
        const bool first = first_statement;
        first_statement = false;
        std::uint64_t vertices = 0, faces = 0;
        if (is_count_line(words, vertices, faces)) {
            if (!first) {
                return fail("count line " + quote(trim(line)) +
                            " ('<vertices> <faces>') is accepted only as the first statement");
            }
            skipped.count_line = 1;
            declared_vertices = vertices;
            declared_faces = faces;
            count_line_number = line_number;
            continue;
        }

        if (keyword == "v") {
            const std::size_t n = words.size() - 1;
            if (n != 3 && n != 4) {
                return fail("vertex has " + std::to_string(n) + " values (expected x y z [w])");
            }
            double xyz[4] = {0, 0, 0, 0};
            for (std::size_t k = 0; k < n; ++k) {
                const NumberStatus st = parse_real(words[k + 1], xyz[k]);
                if (st != NumberStatus::Ok) return fail("vertex " + real_number_problem(words[k + 1], st));
            }
            if (positions.size() >= kMaxVertices) {
                return fail("too many vertices (limit " + std::to_string(kMaxVertices) + ")");
            }
            positions.push_back({xyz[0], xyz[1], xyz[2]});
        } else if (keyword == "f") {
            const std::size_t n = words.size() - 1;
            if (n < 3) return fail("face has " + std::to_string(n) + " vertices (needs at least 3)");
            polygon.clear();
            std::string problem;
            for (std::size_t k = 1; k <= n; ++k) {
                const std::string_view ref = words[k];
                // Up to three '/'-separated fields: v, v/vt, v//vn, v/vt/vn.
                std::string_view fields[3];
                std::size_t count = 0;
                std::size_t start = 0;
                bool malformed = false;
                while (true) {
                    const std::size_t slash = ref.find('/', start);
                    if (count == 3) {
                        malformed = true;
                        break;
                    }
                    fields[count++] = ref.substr(
                        start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
                    if (slash == std::string_view::npos) break;
                    start = slash + 1;
                }
                // Empty fields are allowed only for the texture slot of v//vn.
                if (!malformed) {
                    malformed = fields[0].empty() || (count == 2 && fields[1].empty()) ||
                                (count == 3 && fields[2].empty());
                }
                if (malformed)
                    return fail("malformed face vertex " + quote(ref) +
                                " (expected v, v/vt, v//vn or v/vt/vn)");
                std::uint64_t index = 0;
                if (!resolve_reference(fields[0], positions.size(), "face index", "vertex list", index,
                                       problem)) {
                    return fail(problem);
                }
                std::uint64_t ignored = 0;
                if (count >= 2 && !fields[1].empty() &&
                    !resolve_reference(fields[1], texcoord_count, "texture coordinate index",
                                       "texture coordinate list", ignored, problem)) {
                    return fail(problem);
                }
                if (count == 3 && !resolve_reference(fields[2], normal_count, "normal index", "normal list",
                                                     ignored, problem)) {
                    return fail(problem);
                }
                polygon.push_back(static_cast<std::uint32_t>(index));
            }
            if (current_object == SIZE_MAX) {
                const auto [it, inserted] = object_by_name.try_emplace(current_name, objects.size());
                if (inserted) objects.push_back({current_name, {}});
                current_object = it->second;
            }
            ++face_count;
            std::vector<Tri>& tris = objects[current_object].triangles;
            for (std::size_t k = 1; k + 1 < polygon.size(); ++k)
                tris.push_back({polygon[0], polygon[k], polygon[k + 1]});
        } else if (keyword == "o" || keyword == "g") {
            std::string name;
            for (std::size_t k = 1; k < words.size(); ++k) {
                if (k > 1) name += ' ';
                name.append(words[k]);
            }
            current_name = name.empty() ? stem : stem + "/" + name;
            const auto it = object_by_name.find(current_name);
            current_object = it == object_by_name.end() ? SIZE_MAX : it->second;
        } else if (std::uint64_t* counter = skipped_counter(keyword, skipped)) {
            ++*counter;
        } else {
            return fail("unknown or unsupported statement " + quote(keyword));
        }
    }

    if (skipped.count_line != 0 && (declared_vertices != positions.size() || declared_faces != face_count)) {
        return Error{source + ":" + std::to_string(count_line_number) + ": the count line says " +
                     count_of(declared_vertices, "vertex", "vertices") + " and " + count_of(declared_faces, "face", "faces") +
                     " but the file has " + count_of(positions.size(), "vertex", "vertices") + " and " +
                     count_of(face_count, "face", "faces")};
    }
    if (objects.empty()) return Error{source + ": no triangles (the file has no faces)"};
    skipped_out = skipped;
    std::vector<Mesh> meshes;
    if (objects.size() == 1) {
        // One object: keep the file's vertex list and numbering as is, unreferenced vertices included.
        Mesh mesh;
        mesh.name = std::move(objects[0].name);
        mesh.positions = std::move(positions);
        mesh.triangles = std::move(objects[0].triangles);
        meshes.push_back(std::move(mesh));
        return meshes;
    }
    std::vector<std::uint32_t> scratch(positions.size(), 0xFFFFFFFFu);
    meshes.reserve(objects.size());
    for (const ObjObject& object : objects) meshes.push_back(compact(object, positions, scratch));
    return meshes;
}

}  // namespace cullide::mesh_io_detail

// scene_kit.cpp: the geometry helpers shared by the scene generators.
#include "scenes/scene_kit.h"

#include <cassert>
#include <cmath>
#include <vector>

#include "scene_math.h"

namespace cullide::scene_kit {

Vec3 normalized(Vec3 v) {
    const double len = std::sqrt(dot(v, v));
    return {v.x / len, v.y / len, v.z / len};
}

Vec3 perpendicular(Vec3 w) {
    // Cross with the axis w is least aligned with, chosen by comparing magnitudes (exact), so the
    // result never degenerates.
    const double ax = w.x < 0 ? -w.x : w.x;
    const double ay = w.y < 0 ? -w.y : w.y;
    const double az = w.z < 0 ? -w.z : w.z;
    Vec3 other{0, 0, 1};
    if (ax <= ay && ax <= az) {
        other = {1, 0, 0};
    } else if (ay <= az) {
        other = {0, 1, 0};
    }
    return normalized(cross(w, other));
}

Vec3 apply(const Rotation& r, Vec3 p) { return (p.x * r.u + p.y * r.v) + p.z * r.w; }

Rotation rotation_from_angles(double yaw, double pitch, double roll) {
    double sa = 0, ca = 0, sb = 0, cb = 0, sc = 0, cc = 0;
    det::det_sincos(yaw, sa, ca);
    det::det_sincos(pitch, sb, cb);
    det::det_sincos(roll, sc, cc);
    // Columns of Rz(a) Ry(b) Rx(c).
    Rotation r;
    r.u = {ca * cb, sa * cb, -sb};
    r.v = {ca * sb * sc - sa * cc, sa * sb * sc + ca * cc, cb * sc};
    r.w = {ca * sb * cc + sa * sc, sa * sb * cc - ca * sc, cb * cc};
    return r;
}

Rotation rotation_about(Vec3 axis, double angle) {
    double s = 0, c = 0;
    det::det_sincos(angle, s, c);
    const double t = 1.0 - c;
    const double x = axis.x, y = axis.y, z = axis.z;
    Rotation r;
    r.u = {t * x * x + c, t * x * y + s * z, t * x * z - s * y};
    r.v = {t * x * y - s * z, t * y * y + c, t * y * z + s * x};
    r.w = {t * x * z + s * y, t * y * z - s * x, t * z * z + c};
    return r;
}

Rotation rotation_to(Vec3 w) {
    Rotation r;
    r.w = w;
    r.u = perpendicular(w);
    r.v = cross(w, r.u);
    return r;
}

std::int64_t round_at_least(double x, std::int64_t lo) {
    const auto n = static_cast<std::int64_t>(std::floor(x + 0.5));
    return n < lo ? lo : n;
}

void append_grid(Mesh& mesh, int cols, int rows, bool wrap_cols, bool wrap_rows,
                 const std::function<Vec3(int, int)>& at) {
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    const int stride = wrap_cols ? cols : cols + 1;
    const int row_count = wrap_rows ? rows : rows + 1;
    for (int j = 0; j < row_count; ++j) {
        for (int i = 0; i < stride; ++i) mesh.positions.push_back(at(i, j));
    }
    auto id = [&](int i, int j) {
        if (wrap_cols && i == cols) i = 0;
        if (wrap_rows && j == rows) j = 0;
        return base + static_cast<std::uint32_t>(j * stride + i);
    };
    for (int j = 0; j < rows; ++j) {
        for (int i = 0; i < cols; ++i) {
            const std::uint32_t v00 = id(i, j), v10 = id(i + 1, j), v11 = id(i + 1, j + 1), v01 = id(i, j + 1);
            mesh.triangles.push_back({v00, v10, v11});
            mesh.triangles.push_back({v00, v11, v01});
        }
    }
}

void compact_vertices(Mesh& mesh) {
    constexpr std::uint32_t kUnused = 0xFFFFFFFFu;
    std::vector<std::uint32_t> remap(mesh.positions.size(), kUnused);
    for (const Tri& t : mesh.triangles) {
        for (std::uint32_t v : t) remap[v] = 0;
    }
    std::vector<Vec3> kept;
    for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
        if (remap[i] == kUnused) continue;
        remap[i] = static_cast<std::uint32_t>(kept.size());
        kept.push_back(mesh.positions[i]);
    }
    for (Tri& t : mesh.triangles) {
        for (std::uint32_t& v : t) v = remap[v];
    }
    mesh.positions = std::move(kept);
}

Mesh make_blob(const std::string& name, std::int64_t triangles, const std::function<Vec3(Vec3)>& at) {
    assert(triangles >= 8);
    // c columns and n rings give 2 c n triangles; prefer a c near sqrt(T/2) that divides T/2 so the
    // surface stays closed.
    const std::int64_t c0 = round_at_least(std::sqrt(static_cast<double>(triangles) / 2.0), 3);
    std::int64_t cols = c0;
    if (triangles % 2 == 0) {
        const std::int64_t half = triangles / 2;
        for (std::int64_t d = 0; d <= c0 / 5; ++d) {
            if (half % (c0 + d) == 0) {
                cols = c0 + d;
                break;
            }
            if (c0 - d >= 3 && half % (c0 - d) == 0) {
                cols = c0 - d;
                break;
            }
        }
    }
    const std::int64_t rings = (triangles + 2 * cols - 1) / (2 * cols);
    Mesh mesh;
    mesh.name = name;
    mesh.positions.push_back(at({0, 0, 1}));
    for (std::int64_t i = 1; i <= rings; ++i) {
        double st = 0, ct = 0;
        det::det_sincos(det::kPi * (static_cast<double>(i) / static_cast<double>(rings + 1)), st, ct);
        for (std::int64_t j = 0; j < cols; ++j) {
            double sp = 0, cp = 0;
            det::det_sincos(det::kTwoPi * (static_cast<double>(j) / static_cast<double>(cols)), sp, cp);
            mesh.positions.push_back(at({st * cp, st * sp, ct}));
        }
    }
    mesh.positions.push_back(at({0, 0, -1}));
    const auto bottom = static_cast<std::uint32_t>(mesh.positions.size() - 1);
    auto ring = [&](std::int64_t i, std::int64_t j) {
        return static_cast<std::uint32_t>(1 + (i - 1) * cols + (j % cols));
    };
    for (std::int64_t j = 0; j < cols; ++j) mesh.triangles.push_back({0, ring(1, j), ring(1, j + 1)});
    for (std::int64_t i = 1; i < rings; ++i) {
        for (std::int64_t j = 0; j < cols; ++j) {
            const std::uint32_t a = ring(i, j), b = ring(i, j + 1), c = ring(i + 1, j + 1), d = ring(i + 1, j);
            mesh.triangles.push_back({a, d, c});
            mesh.triangles.push_back({a, c, b});
        }
    }
    for (std::int64_t j = 0; j < cols; ++j) mesh.triangles.push_back({ring(rings, j), bottom, ring(rings, j + 1)});
    mesh.triangles.resize(static_cast<std::size_t>(triangles));
    compact_vertices(mesh);
    return mesh;
}

}  // namespace cullide::scene_kit

// A downstream program on the installed cullide::eigen front door: two unit squares (two triangles
// each, libigl-style V/F), the second crossing the first's plane. Exit status 0 only when the pairs
// are the ones worked out by hand.
#include <cstdio>

#include <Eigen/Core>

#include "cullide/eigen.h"

int main() {
    Eigen::MatrixXd V1(4, 3), V2(4, 3);
    Eigen::MatrixXi F(2, 3);
    V1 << 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0;                     // the square [0,1]^2 at z = 0
    V2 << 0.25, 0.6, -1, 0.25, 0.6, 1, 0.25, 0.8, 1, 0.25, 0.8, -1;  // a wall at x = 0.25
    F << 0, 1, 2, 0, 2, 3;
    // The wall crosses z = 0 along x = 0.25, 0.6 <= y <= 0.8: inside triangle 1 of the square only
    // (triangle 0 holds y <= x); wall triangle 0 meets it for y in [0.6, 0.7], triangle 1 for [0.7, 0.8].
    cullide::RunOptions options;
    options.method = cullide::Method::Exact;
    auto r = cullide::collide(V1, F, V2, F, options);
    if (!r) return std::fprintf(stderr, "eigen_check: %s\n", r.error().message.c_str()), 1;
    const cullide::PairMatrix& m = r.value().pairs;
    std::printf("eigen_check: %d pairs\n", static_cast<int>(m.rows()));
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
        std::printf("  %d %d %d %d\n", m(i, 0), m(i, 1), m(i, 2), m(i, 3));
    }
    return m.rows() == 2 && m(0, 1) == 1 && m(1, 1) == 1 && m(0, 3) == 0 && m(1, 3) == 1 ? 0 : 1;
}

// Per-element kernels of the anisotropic and point-cloud Laplacians.
//
// Python validates every input (shapes, dtypes, index ranges) before calling in here;
// these loops assume valid data. Each function mirrors, operation for operation, the
// NumPy reference in spectral_igl/laplacian (tests compare the two).
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace nb = nanobind;

using InF2 = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using InF3 = nb::ndarray<const double, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
using InF1 = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using InI2 = nb::ndarray<const int64_t, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using OutF = nb::ndarray<nb::numpy, double>;

namespace {

OutF make_array(std::vector<size_t> shape) {
    size_t total = 1;
    for (size_t s : shape) total *= s;
    double *buf = new double[std::max<size_t>(total, 1)];
    std::fill(buf, buf + total, 0.0);
    nb::capsule owner(buf, [](void *p) noexcept { delete[] static_cast<double *>(p); });
    return OutF(buf, shape.size(), shape.data(), owner);
}

inline void cross(const double *a, const double *b, double *c) {
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}
inline double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// 3x3 solve by Gaussian elimination with partial pivoting (as LAPACK gesv).
void solve3(double A[3][3], double b[3], double x[3]) {
    for (int c = 0; c < 3; ++c) {
        int p = c;
        for (int r = c + 1; r < 3; ++r)
            if (std::fabs(A[r][c]) > std::fabs(A[p][c])) p = r;
        if (p != c) {
            for (int j = 0; j < 3; ++j) std::swap(A[c][j], A[p][j]);
            std::swap(b[c], b[p]);
        }
        for (int r = c + 1; r < 3; ++r) {
            double l = A[r][c] / A[c][c];
            for (int j = c; j < 3; ++j) A[r][j] -= l * A[c][j];
            b[r] -= l * b[c];
        }
    }
    for (int c = 2; c >= 0; --c) {
        double s = b[c];
        for (int j = c + 1; j < 3; ++j) s -= A[c][j] * x[j];
        x[c] = s / A[c][c];
    }
}

// Eigen-decomposition of the symmetric [[a, b], [b, c]]: ascending values, unit vectors
// as columns of U (U[row][col]).
void eigh2(double a, double b, double c, double lam[2], double U[2][2]) {
    double m = 0.5 * (a + c), h = 0.5 * (a - c);
    double r = std::hypot(h, b);
    lam[0] = m - r;
    lam[1] = m + r;
    double th = 0.5 * std::atan2(b, h);  // direction of the larger eigenvalue
    double cs = std::cos(th), sn = std::sin(th);
    U[0][1] = cs;
    U[1][1] = sn;
    U[0][0] = -sn;
    U[1][0] = cs;
}

}  // namespace

// Principal curvatures/directions per face and the anisotropic stiffness per face.
nb::tuple anisotropic_faces(InF2 V_, InI2 F_, double alpha) {
    const size_t n = V_.shape(0), m = F_.shape(0);
    const double *V = V_.data();
    const int64_t *F = F_.data();
    OutF kappa_ = make_array({m, 2}), dirs_ = make_array({m, 2, 3}), K_ = make_array({m, 3, 3});
    double *kappa = kappa_.data(), *dirs = dirs_.data(), *K = K_.data();
    {
        nb::gil_scoped_release release;
        std::vector<double> E(9 * m), Nf(3 * m), dbl(m), Fr(6 * m), S3(9 * m);
        std::vector<double> vn(3 * n, 0.0), Sv(9 * n, 0.0), wv(n, 0.0);
        for (size_t f = 0; f < m; ++f) {
            const double *p0 = V + 3 * F[3 * f], *p1 = V + 3 * F[3 * f + 1], *p2 = V + 3 * F[3 * f + 2];
            double *e = &E[9 * f];
            for (int i = 0; i < 3; ++i) {
                e[i] = p2[i] - p1[i];      // opposite vertex 0
                e[3 + i] = p0[i] - p2[i];  // opposite vertex 1
                e[6 + i] = p1[i] - p0[i];  // opposite vertex 2
            }
            double me1[3] = {-e[3], -e[4], -e[5]}, N[3];
            cross(e + 6, me1, N);
            double d = std::sqrt(dot(N, N));
            dbl[f] = d;
            for (int i = 0; i < 3; ++i) Nf[3 * f + i] = N[i] / d;
            for (int a = 0; a < 3; ++a)
                for (int i = 0; i < 3; ++i) vn[3 * F[3 * f + a] + i] += N[i];
        }
        for (size_t v = 0; v < n; ++v) {
            double *x = &vn[3 * v];
            double r = std::sqrt(dot(x, x));
            for (int i = 0; i < 3; ++i) x[i] = r > 0 ? x[i] / r : 0.0;
        }
        static const int pq[3][2] = {{1, 2}, {2, 0}, {0, 1}};
        for (size_t f = 0; f < m; ++f) {
            const double *e = &E[9 * f], *nf = &Nf[3 * f];
            double *u = &Fr[6 * f], *w = u + 3;
            double le = std::sqrt(dot(e + 6, e + 6));
            for (int i = 0; i < 3; ++i) u[i] = e[6 + i] / le;
            cross(nf, u, w);
            double AtA[3][3] = {{0}}, Atb[3] = {0};
            for (int k = 0; k < 3; ++k) {
                const double *vp = &vn[3 * F[3 * f + pq[k][0]]], *vq = &vn[3 * F[3 * f + pq[k][1]]];
                double dn[3] = {vq[0] - vp[0], vq[1] - vp[1], vq[2] - vp[2]};
                double eu = dot(e + 3 * k, u), ew = dot(e + 3 * k, w);
                double du = dot(dn, u), dw = dot(dn, w);
                double r1[3] = {eu, ew, 0.0}, r2[3] = {0.0, eu, ew};
                for (int i = 0; i < 3; ++i) {
                    for (int j = 0; j < 3; ++j) AtA[i][j] += r1[i] * r1[j] + r2[i] * r2[j];
                    Atb[i] += r1[i] * du + r2[i] * dw;
                }
            }
            double tr = AtA[0][0] + AtA[1][1] + AtA[2][2];
            for (int i = 0; i < 3; ++i) AtA[i][i] += 1e-12 * tr;
            double x[3];
            solve3(AtA, Atb, x);
            double S2[2][2] = {{x[0], x[1]}, {x[1], x[2]}};
            double *s3 = &S3[9 * f];
            bool finite = true;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    double s = 0.0;
                    for (int a = 0; a < 2; ++a)
                        for (int b = 0; b < 2; ++b) s += Fr[6 * f + 3 * a + i] * S2[a][b] * Fr[6 * f + 3 * b + j];
                    s3[3 * i + j] = s;
                    finite = finite && std::isfinite(s);
                }
            for (int i = 0; i < 9; ++i)
                if (!std::isfinite(s3[i])) s3[i] = 0.0;
            double area = 0.5 * dbl[f];
            for (int a = 0; a < 3; ++a) {
                int64_t v = F[3 * f + a];
                for (int i = 0; i < 9; ++i) Sv[9 * v + i] += s3[i] * area;
                wv[v] += area;
            }
        }
        for (size_t v = 0; v < n; ++v) {
            double d = wv[v] > 0 ? wv[v] : 1.0;
            for (int i = 0; i < 9; ++i) Sv[9 * v + i] /= d;
        }
        for (size_t f = 0; f < m; ++f) {
            double Sf[9];
            const double *a0 = &Sv[9 * F[3 * f]], *a1 = &Sv[9 * F[3 * f + 1]], *a2 = &Sv[9 * F[3 * f + 2]];
            for (int i = 0; i < 9; ++i) Sf[i] = (a0[i] + a1[i] + a2[i]) / 3.0;
            const double *fr = &Fr[6 * f];
            double S2[2][2];
            for (int a = 0; a < 2; ++a)
                for (int b = 0; b < 2; ++b) {
                    double s = 0.0;
                    for (int i = 0; i < 3; ++i)
                        for (int j = 0; j < 3; ++j) s += fr[3 * a + i] * Sf[3 * i + j] * fr[3 * b + j];
                    S2[a][b] = s;
                }
            double off = 0.5 * (S2[0][1] + S2[1][0]);
            double lam[2], U[2][2];
            eigh2(S2[0][0], off, S2[1][1], lam, U);
            kappa[2 * f] = lam[0];
            kappa[2 * f + 1] = lam[1];
            double *dr = &dirs[6 * f];
            for (int b = 0; b < 2; ++b)
                for (int i = 0; i < 3; ++i) dr[3 * b + i] = U[0][b] * fr[i] + U[1][b] * fr[3 + i];
            // P1 gradients grad phi_a = (n x e_a) / (2A), then K = A G D G^T
            const double *e = &E[9 * f], *nf = &Nf[3 * f];
            double G[3][3];
            for (int a = 0; a < 3; ++a) {
                cross(nf, e + 3 * a, G[a]);
                for (int i = 0; i < 3; ++i) G[a][i] /= dbl[f];
            }
            double *k = &K[9 * f];
            double area = 0.5 * dbl[f];
            if (alpha == 0.0) {
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b) k[3 * a + b] = dot(G[a], G[b]) * area;
            } else {
                double ph[2] = {1.0 / (1.0 + alpha * std::fabs(lam[0])), 1.0 / (1.0 + alpha * std::fabs(lam[1]))};
                double Gd[3][2];
                for (int a = 0; a < 3; ++a)
                    for (int c = 0; c < 2; ++c) Gd[a][c] = dot(G[a], dr + 3 * c);
                for (int a = 0; a < 3; ++a)
                    for (int b = 0; b < 3; ++b)
                        k[3 * a + b] = (Gd[a][0] * ph[0] * Gd[b][0] + Gd[a][1] * ph[1] * Gd[b][1]) * area;
            }
        }
    }
    return nb::make_tuple(kappa_, dirs_, K_);
}

// Area of the Voronoi cell of the origin among the 2-D points Q (n, k, 2), clipped to the
// square [-half, half]^2 (Sutherland--Hodgman by the bisector half-planes x.q <= |q|^2/2).
OutF clip_cells(InF3 Q_, InF1 half_) {
    const size_t n = Q_.shape(0), k = Q_.shape(1);
    const double *Q = Q_.data(), *half = half_.data();
    OutF A_ = make_array({n});
    double *A = A_.data();
    {
        nb::gil_scoped_release release;
        std::vector<double> poly, out;
        poly.reserve(2 * (k + 8));
        out.reserve(2 * (k + 8));
        for (size_t p = 0; p < n; ++p) {
            double s = half[p];
            poly.assign({-s, -s, s, -s, s, s, -s, s});
            for (size_t j = 0; j < k && !poly.empty(); ++j) {
                double qx = Q[2 * (p * k + j)], qy = Q[2 * (p * k + j) + 1];
                double c = 0.5 * (qx * qx + qy * qy);
                size_t mcount = poly.size() / 2;
                out.clear();
                for (size_t a = 0; a < mcount; ++a) {
                    size_t b = (a + 1) % mcount;
                    double xa = poly[2 * a], ya = poly[2 * a + 1], xb = poly[2 * b], yb = poly[2 * b + 1];
                    double fa = xa * qx + ya * qy - c, fb = xb * qx + yb * qy - c;
                    bool ina = fa <= 0, inb = fb <= 0;
                    if (ina) {
                        out.push_back(xa);
                        out.push_back(ya);
                    }
                    if (ina != inb) {
                        double t = fa / (fa - fb);
                        out.push_back(xa + t * (xb - xa));
                        out.push_back(ya + t * (yb - ya));
                    }
                }
                poly.swap(out);
            }
            size_t mcount = poly.size() / 2;
            if (mcount < 3) {
                A[p] = 0.0;
                continue;
            }
            double s2 = 0.0;
            for (size_t a = 0; a < mcount; ++a) {
                size_t b = (a + 1) % mcount;
                s2 += poly[2 * a] * poly[2 * b + 1] - poly[2 * b] * poly[2 * a + 1];
            }
            A[p] = 0.5 * std::fabs(s2);
        }
    }
    return A_;
}

// Intrinsic Delaunay triangulation by edge flips (Fisher et al. 2007; Sharp and Crane 2020):
// F (m, 3) and edge lengths l (m, 3), l[f, i] opposite corner i. Every interior manifold edge
// whose opposite angles sum to more than pi is flipped (a stack of suspect edges, each flip
// pushing the four edges of its quad) until all are Delaunay; boundary and non-manifold
// edges are never flipped. Returns (l, F) of the intrinsic Delaunay triangulation, the
// same arrays as libigl's intrinsic_delaunay_triangulation.
inline double cot_opposite(const double *L, int i) {
    // cotangent of the angle at corner i of a triangle with edge lengths L
    double a = L[i], b = L[(i + 1) % 3], c = L[(i + 2) % 3];
    double s = 0.5 * (a + b + c);
    double area2 = s * (s - a) * (s - b) * (s - c);
    double area = area2 > 0 ? std::sqrt(area2) : 0.0;
    return (b * b + c * c - a * a) / (4.0 * std::max(area, 1e-300));
}

nb::tuple intrinsic_flips(InF2 l_, InI2 F_) {
    const size_t m = F_.shape(0);
    OutF lo_ = make_array({m, 3});
    int64_t *Fo = new int64_t[std::max<size_t>(3 * m, 1)];
    nb::capsule owner(Fo, [](void *p) noexcept { delete[] static_cast<int64_t *>(p); });
    size_t shp[2] = {m, 3};
    nb::ndarray<nb::numpy, int64_t> Fo_(Fo, 2, shp, owner);
    double *L = lo_.data();
    std::copy(l_.data(), l_.data() + 3 * m, L);
    std::copy(F_.data(), F_.data() + 3 * m, Fo);
    size_t flips = 0;
    {
        nb::gil_scoped_release release;
        // twin halfedges: h = 3 f + i is the edge opposite corner i of face f. The
        // halfedges are bucketed by their smaller vertex (a counting sort, in order of h),
        // then matched by the larger one within each bucket
        int64_t nv = 0;
        for (size_t k = 0; k < 3 * m; ++k) nv = std::max(nv, Fo[k] + 1);
        std::vector<int64_t> bptr(nv + 1, 0), bkt(3 * m), other(3 * m);
        for (size_t f = 0; f < m; ++f)
            for (int i = 0; i < 3; ++i) {
                int64_t a = Fo[3 * f + (i + 1) % 3], b = Fo[3 * f + (i + 2) % 3];
                bptr[std::min(a, b) + 1]++;
                other[3 * f + i] = std::max(a, b);
            }
        for (int64_t v = 0; v < nv; ++v) bptr[v + 1] += bptr[v];
        {
            std::vector<int64_t> pos(bptr.begin(), bptr.end() - 1);
            for (size_t f = 0; f < m; ++f)
                for (int i = 0; i < 3; ++i) {
                    int64_t a = Fo[3 * f + (i + 1) % 3], b = Fo[3 * f + (i + 2) % 3];
                    bkt[pos[std::min(a, b)]++] = int64_t(3 * f + i);
                }
        }
        std::vector<int64_t> twin(3 * m, -1);
        std::vector<std::pair<int64_t, int64_t>> group;
        for (int64_t v = 0; v < nv; ++v) {
            group.clear();
            for (int64_t k = bptr[v]; k < bptr[v + 1]; ++k) group.push_back({other[bkt[k]], bkt[k]});
            std::sort(group.begin(), group.end());
            for (size_t s0 = 0; s0 < group.size();) {
                size_t e = s0;
                while (e < group.size() && group[e].first == group[s0].first) ++e;
                if (e - s0 == 2) {
                    twin[group[s0].second] = group[s0 + 1].second;
                    twin[group[s0 + 1].second] = group[s0].second;
                } else if (e - s0 > 2) {
                    for (size_t k = s0; k < e; ++k) twin[group[k].second] = -2;   // non-manifold
                }
                s0 = e;
            }
        }
        std::vector<int64_t> stack;
        std::vector<char> queued(3 * m, 0);
        stack.reserve(3 * m);
        for (size_t h = 0; h < 3 * m; ++h)
            if (twin[h] >= 0 && (int64_t)h < twin[h]) {
                stack.push_back((int64_t)h);
                queued[h] = 1;
            }
        const size_t max_flips = 200 * (m + 10);
        while (!stack.empty() && flips < max_flips) {
            int64_t h = stack.back();
            stack.pop_back();
            queued[h] = 0;
            int64_t g = twin[h];
            if (g < 0) continue;
            int64_t f = h / 3, f2 = g / 3;
            int i = (int)(h % 3), j = (int)(g % 3);
            if (f == f2) continue;
            if (cot_opposite(L + 3 * f, i) + cot_opposite(L + 3 * f2, j) >= -1e-12) continue;
            int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            int64_t a = Fo[3 * f + i], b = Fo[3 * f + i1], c = Fo[3 * f + i2], d = Fo[3 * f2 + j];
            // j1 must be f2's corner at c and j2 its corner at b: true when f2 is oriented
            // like f, swapped when the two faces disagree (meshes need not be oriented)
            if (Fo[3 * f2 + j1] != c) std::swap(j1, j2);
            double bc = L[3 * f + i], ca = L[3 * f + i1], ab = L[3 * f + i2];
            double bd = L[3 * f2 + j1], dc = L[3 * f2 + j2];
            // unfold the quad: b at the origin, c on the x axis, a above and d below
            double xa = (ab * ab + bc * bc - ca * ca) / (2.0 * bc);
            double ya = std::sqrt(std::max(ab * ab - xa * xa, 0.0));
            double xd = (bd * bd + bc * bc - dc * dc) / (2.0 * bc);
            double yd = -std::sqrt(std::max(bd * bd - xd * xd, 0.0));
            double ad = std::hypot(xa - xd, ya - yd);
            int64_t t_ab = twin[3 * f + i2], t_ca = twin[3 * f + i1];
            int64_t t_bd = twin[3 * f2 + j1], t_dc = twin[3 * f2 + j2];
            // new faces (a, b, d) and (d, c, a)
            Fo[3 * f] = a; Fo[3 * f + 1] = b; Fo[3 * f + 2] = d;
            L[3 * f] = bd; L[3 * f + 1] = ad; L[3 * f + 2] = ab;
            Fo[3 * f2] = d; Fo[3 * f2 + 1] = c; Fo[3 * f2 + 2] = a;
            L[3 * f2] = ca; L[3 * f2 + 1] = ad; L[3 * f2 + 2] = dc;
            int64_t nh[6] = {3 * f, 3 * f + 1, 3 * f + 2, 3 * f2, 3 * f2 + 1, 3 * f2 + 2};
            int64_t nt[6] = {t_bd, 3 * f2 + 1, t_ab, t_ca, 3 * f + 1, t_dc};
            for (int k = 0; k < 6; ++k) {
                twin[nh[k]] = nt[k];
                if (nt[k] >= 0) twin[nt[k]] = nh[k];
            }
            for (int k : {0, 2, 3, 5})
                if (twin[nh[k]] >= 0 && !queued[nh[k]]) {
                    stack.push_back(nh[k]);
                    queued[nh[k]] = 1;
                }
            ++flips;
        }
    }
    return nb::make_tuple(lo_, Fo_, flips);
}

// Sum of per-triangle 3 x 3 element matrices W[f] placed at the vertices F[f]: the (n, n)
// CSR arrays (indptr, indices, data) with sorted rows, duplicates summed in face order, and
// every diagonal entry stored (a zero at vertices no face references).
nb::tuple element_sum(InF3 W_, InI2 F_, int64_t n) {
    const size_t m = F_.shape(0);
    const double *W = W_.data();
    const int64_t *F = F_.data();
    std::vector<int64_t> cnt(n + 1, 0);
    for (size_t k = 0; k < 3 * m; ++k) cnt[F[k] + 1] += 3;
    for (int64_t i = 0; i < n; ++i) cnt[i + 1] += cnt[i] + 1;   // + 1: the diagonal
    const int64_t total = cnt[n];
    std::vector<int64_t> col(total);
    std::vector<double> val(total);
    std::vector<int64_t> pos(cnt.begin(), cnt.end() - 1);
    {
        nb::gil_scoped_release release;
        for (int64_t i = 0; i < n; ++i) { col[pos[i]] = i; val[pos[i]++] = 0.0; }
        for (size_t f = 0; f < m; ++f)
            for (int a = 0; a < 3; ++a) {
                int64_t i = F[3 * f + a];
                for (int b = 0; b < 3; ++b) {
                    col[pos[i]] = F[3 * f + b];
                    val[pos[i]++] = W[9 * f + 3 * a + b];
                }
            }
    }
    // sort each row by column (stably: duplicates are summed in face order) and merge
    std::vector<int64_t> rowptr(n + 1, 0);
    std::vector<std::pair<int64_t, double>> row;
    int64_t q = 0;
    {
        nb::gil_scoped_release release;
        for (int64_t i = 0; i < n; ++i) {
            row.clear();
            for (int64_t k = cnt[i]; k < cnt[i + 1]; ++k) row.push_back({col[k], val[k]});
            if (row.size() <= 64) {   // insertion sort (stable) of a typical short row
                for (size_t a = 1; a < row.size(); ++a) {
                    auto x = row[a];
                    size_t b = a;
                    for (; b > 0 && row[b - 1].first > x.first; --b) row[b] = row[b - 1];
                    row[b] = x;
                }
            } else {
                std::stable_sort(row.begin(), row.end(),
                                 [](const auto &x, const auto &y) { return x.first < y.first; });
            }
            for (size_t k = 0; k < row.size();) {
                int64_t c = row[k].first;
                double v = 0.0;
                for (; k < row.size() && row[k].first == c; ++k) v += row[k].second;
                col[q] = c;
                val[q++] = v;
            }
            rowptr[i + 1] = q;
        }
    }
    if (q >= (int64_t(1) << 31)) throw std::overflow_error("element_sum: more than 2^31 entries");
    int32_t *ip = new int32_t[n + 1];
    nb::capsule oip(ip, [](void *p) noexcept { delete[] static_cast<int32_t *>(p); });
    int32_t *ix = new int32_t[std::max<int64_t>(q, 1)];
    nb::capsule oix(ix, [](void *p) noexcept { delete[] static_cast<int32_t *>(p); });
    OutF data = make_array({size_t(q)});
    for (int64_t i = 0; i <= n; ++i) ip[i] = int32_t(rowptr[i]);
    for (int64_t k = 0; k < q; ++k) { ix[k] = int32_t(col[k]); data.data()[k] = val[k]; }
    size_t sp[1] = {size_t(n + 1)}, sx[1] = {size_t(q)};
    return nb::make_tuple(nb::ndarray<nb::numpy, int32_t>(ip, 1, sp, oip),
                          nb::ndarray<nb::numpy, int32_t>(ix, 1, sx, oix), data);
}

// The heat method's middle step on per-triangle hat gradients (gx, gy) (m, 3) in each
// triangle's frame: X_f = -grad u / |grad u| on each face (zero where grad u vanishes) and
// its integrated divergence div[v] = sum_f A_f X_f . grad phi_v, returned as (n,).
OutF normalized_gradient_divergence(InF1 u_, InF2 gx_, InF2 gy_, InF1 A_, InI2 F_) {
    const size_t m = F_.shape(0), n = u_.shape(0);
    OutF div_ = make_array({n});
    const double *u = u_.data(), *gx = gx_.data(), *gy = gy_.data(), *A = A_.data();
    const int64_t *F = F_.data();
    double *div = div_.data();
    nb::gil_scoped_release release;
    for (size_t f = 0; f < m; ++f) {
        const int64_t *c = F + 3 * f;
        const double *x = gx + 3 * f, *y = gy + 3 * f;
        double sx = 0.0, sy = 0.0;
        for (int a = 0; a < 3; ++a) { sx += x[a] * u[c[a]]; sy += y[a] * u[c[a]]; }
        double nrm = std::sqrt(sx * sx + sy * sy);
        if (!(nrm > 0)) continue;
        double w = -A[f] / nrm;
        sx *= w;
        sy *= w;
        for (int a = 0; a < 3; ++a) div[c[a]] += sx * x[a] + sy * y[a];
    }
    return div_;
}

NB_MODULE(_assembly, m) {
    m.doc() = "Compiled per-element kernels of spectral_igl's Laplacian constructors.";
    m.def("anisotropic_faces", &anisotropic_faces, nb::arg("V"), nb::arg("F"), nb::arg("alpha"),
          "(kappa (m, 2), dirs (m, 2, 3), K (m, 3, 3)) of a clean triangle mesh.");
    m.def("clip_cells", &clip_cells, nb::arg("Q"), nb::arg("half"),
          "(n,) tangent-plane Voronoi cell areas of the origin among Q (n, k, 2).");
    m.def("normalized_gradient_divergence", &normalized_gradient_divergence, nb::arg("u"), nb::arg("gx"),
          nb::arg("gy"), nb::arg("A"), nb::arg("F"),
          "(n,) divergence of -grad u / |grad u| integrated over the faces, from hat gradients gx, gy (m, 3).");
    m.def("element_sum", &element_sum, nb::arg("W"), nb::arg("F"), nb::arg("n"),
          "(indptr, indices, data) of the (n, n) CSR sum of element matrices W (m, 3, 3) at F (m, 3).");
    m.def("intrinsic_flips", &intrinsic_flips, nb::arg("l"), nb::arg("F"),
          "(l, F, flips) of the intrinsic Delaunay triangulation of edge lengths l (m, 3), F (m, 3).");
}

// Multifrontal supernodal LDL^T of sparse symmetric (real or complex symmetric, not
// Hermitian) matrices, with the selected inverse: the diagonal of A^-1 from the factor
// alone (Takahashi et al. 1973; Erisman & Tinney 1975), at about the cost of a second
// factorization.
//
// No pivoting: the matrices factorized here are symmetric positive definite, or complex
// symmetric with a definite real or imaginary part (L - zB with z off the real spectrum),
// whose leading principal minors never vanish. A zero pivot raises.
//
// Python chooses the fill-reducing ordering (METIS nested dissection, or the minimum
// degree of minimum_degree.hpp) and checks every input; Symbolic postorders the elimination tree, finds relaxed supernodes and the
// assembly maps once per sparsity pattern; Factor<T> factorizes values on that pattern.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/shared_ptr.h>
#include <nanobind/stl/string.h>

#include <algorithm>
#include <cmath>
#include <complex>
#include <exception>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "minimum_degree.hpp"

namespace nb = nanobind;
using cplx = std::complex<double>;
using i64 = int64_t;

namespace {

// ------------------------------------------------------------------------- instruction set
// The hot kernels (numeric factorization, solves, selected inversion) are compiled twice,
// for AVX2 and for the x86-64 baseline, and one is chosen at run time by the CPU. The two
// may round differently, so SPECTRAL_IGL_BASELINE=1 in the environment forces the baseline
// on any CPU (to test what machines without AVX2 compute). GCC's target_clones cannot be
// steered so: its resolver asks the CPU (cpuid) directly, before any code of ours runs.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define ISA_AVX2 __attribute__((target("avx2"), noinline))
#define ISA_BASELINE __attribute__((noinline))
#define ISA_BODY __attribute__((always_inline)) inline
#define SERIES_VECTORS 1
namespace isa {
bool avx2() {
    static const bool yes = [] {
        const char *env = std::getenv("SPECTRAL_IGL_BASELINE");
        const bool baseline = env && *env && std::string(env) != "0";
        return !baseline && __builtin_cpu_supports("avx2");
    }();
    return yes;
}
}  // namespace isa
#else
#define ISA_AVX2
#define ISA_BASELINE
#define ISA_BODY inline
#define SERIES_VECTORS 0
namespace isa {
bool avx2() { return false; }
}  // namespace isa
#endif

// ------------------------------------------------------------------------- BLAS
// Level-3 BLAS for the large dense blocks (the fronts near the root), called through the
// function pointers scipy.linalg.cython_blas exports; Python sets them once at import, so
// nothing is linked against a BLAS here. Blocks with fewer than blas::min_work
// multiply-adds keep the loops below (a call costs more than a small block).
namespace blas {
template <class T> using gemm_t = void (*)(char *, char *, int *, int *, int *, T *, T *, int *, T *, int *, T *, T *, int *);
template <class T> using trxm_t = void (*)(char *, char *, char *, char *, int *, int *, T *, T *, int *, T *, int *);
gemm_t<double> dgemm = nullptr;
gemm_t<cplx> zgemm = nullptr;
trxm_t<double> dtrsm = nullptr, dtrmm = nullptr;
trxm_t<cplx> ztrsm = nullptr, ztrmm = nullptr;
double min_work = 32768.0;

bool ready() { return dgemm && zgemm && dtrsm && dtrmm && ztrsm && ztrmm; }
inline bool use(double work) { return work >= min_work && ready(); }

// front_blas's column blocks: the panel's and the trailing update's
constexpr int front_nb = 64, front_cb = 128;

// The largest BLAS calls of an operation, asked before it runs (the thread policy of
// spectral_igl/linalg/threads.py): the largest m*n*k of its gemms, and the largest smaller
// side min(m, n) of its trsm and trmm
struct Largest {
    double gemm = 0.0;
    int trxm = 0;
    void add_gemm(double m, double n, double k) {
        if (m > 0 && n > 0 && k > 0) gemm = std::max(gemm, m * n * k);
    }
    void add_trxm(int m, int n) { trxm = std::max(trxm, std::min(m, n)); }
};

inline gemm_t<double> gemm_of(double *) { return dgemm; }
inline gemm_t<cplx> gemm_of(cplx *) { return zgemm; }

// C (m x n, ldc) = alpha op(A) op(B) + beta C, column-major; op is 'N' or 'T' (never conjugated)
template <class T>
void gemm(char ta, char tb, int m, int n, int k, T alpha, const T *A, int lda, const T *B, int ldb, T beta, T *C, int ldc) {
    if (m <= 0 || n <= 0) return;
    if (k <= 0) {   // C = beta C
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < m; ++i) C[size_t(j) * ldc + i] = beta == T(0) ? T(0) : beta * C[size_t(j) * ldc + i];
        return;
    }
    gemm_of(static_cast<T *>(nullptr))(&ta, &tb, &m, &n, &k, &alpha, const_cast<T *>(A), &lda,
                                         const_cast<T *>(B), &ldb, &beta, C, &ldc);
}

// B (m x n, ldb) = alpha op(A)^-1 B / alpha B op(A)^-1 (trsm, side 'L' / 'R') or
// alpha op(A) B (trmm), A triangular
template <class T>
void trxm(bool solve, char side, char uplo, char ta, char diag, int m, int n, T alpha, const T *A, int lda, T *B, int ldb) {
    if (m <= 0 || n <= 0) return;
    trxm_t<T> f;
    if constexpr (std::is_same_v<T, double>) f = solve ? dtrsm : dtrmm; else f = solve ? ztrsm : ztrmm;
    f(&side, &uplo, &ta, &diag, &m, &n, &alpha, const_cast<T *>(A), &lda, B, &ldb);
}
template <class T>
void trsm(char side, char uplo, char ta, char diag, int m, int n, T alpha, const T *A, int lda, T *B, int ldb) {
    trxm<T>(true, side, uplo, ta, diag, m, n, alpha, A, lda, B, ldb);
}
template <class T>
void trmm(char side, char uplo, char ta, char diag, int m, int n, T alpha, const T *A, int lda, T *B, int ldb) {
    trxm<T>(false, side, uplo, ta, diag, m, n, alpha, A, lda, B, ldb);
}
}  // namespace blas

// ------------------------------------------------------------------------- symbolic
struct Symbolic {
    int n = 0;
    i64 nnz_in = 0;
    std::vector<int> perm;      // internal q -> original perm[q]
    int ns = 0;                 // supernodes
    std::vector<int> first;     // ns + 1 column ranges
    std::vector<i64> rptr;      // ns + 1 offsets into rows
    std::vector<int> rows;      // row lists: the supernode's columns, then R' (sorted)
    std::vector<int> sparent;   // parent supernode or -1
    std::vector<int> nchild;
    std::vector<i64> lptr;      // ns + 1 offsets of the m x nc panels
    std::vector<i64> relptr;    // ns + 1 offsets into rel
    std::vector<int> rel;       // positions of R'_J in the parent's row list
    std::vector<i64> aptr;      // ns + 1 offsets into asrc/adst
    std::vector<i64> asrc;      // index into the input values
    std::vector<i64> adst;      // position in the m x m frontal matrix (column-major)
    std::vector<i64> amirror;   // index into the input values of the mirror entry, -1 on the diagonal
    i64 nnz_L = 0;              // stored entries of L (panels)
    double flops = 0.0;

    int m(int J) const { return int(rptr[J + 1] - rptr[J]); }

    // index of the input entry (row r, column c), -1 when the pattern has none
    static i64 mirror_of(const int *indptr, const int *indices, int c, int r) {
        for (i64 k = indptr[c]; k < indptr[c + 1]; ++k)
            if (indices[k] == r) return k;
        return -1;
    }
    int nc(int J) const { return first[J + 1] - first[J]; }

    // multiply-adds of supernode J's dense block in the factorization, in a substitution of
    // k columns and in the selected inversion: the block goes to the BLAS from blas::min_work
    double factor_work(int J) const { const double c = nc(J), r = m(J) - c; return c * c * (c + r) + r * r * c; }
    double solve_work(int J, double k) const { return double(m(J)) * nc(J) * k; }
    double inverse_work(int J) const { const double c = nc(J), r = m(J) - c; return r * r * c + c * c * (c + r); }

    // The largest BLAS calls of the numeric factorization ("factor"), of a solve of k
    // columns ("solve"; inverse_columns of k columns makes at most these) or of the
    // selected inversion ("inverse"), call for call as Factor makes them
    blas::Largest largest_blas(const std::string &op, int k) const {
        if (op != "factor" && op != "solve" && op != "inverse")
            throw std::invalid_argument("op must be 'factor', 'solve' or 'inverse', got '" + op + "'");
        const char o = op[0];
        blas::Largest out;
        for (int J = 0; J < ns; ++J) {
            const int c = nc(J), mr = m(J) - c;
            if (o == 'f' && blas::use(factor_work(J))) {
                // front_blas: the panel's first (largest) gemm, the trailing update's first
                const int w = std::min(c, blas::front_nb);
                if (w < c) out.add_gemm(m(J) - w, c - w, w);
                out.add_gemm(mr, std::min(blas::front_cb, mr), c);
            } else if (o == 's' && blas::use(solve_work(J, k))) {
                out.add_trxm(k, c);
                out.add_gemm(k, mr, c);
            } else if (o == 'i' && blas::use(inverse_work(J))) {
                out.add_trxm(mr, c);
                out.add_trxm(c, c);
                out.add_gemm(mr, c, mr);
                out.add_gemm(c, c, mr);
            }
        }
        return out;
    }

    Symbolic(int n_, const int *indptr, const int *indices, i64 nnz, const int *p0) : n(n_), nnz_in(nnz) {
        // inverse of the given ordering
        std::vector<int> inv0(n);
        for (int q = 0; q < n; ++q) inv0[p0[q]] = q;
        // upper pattern in the METIS labels: for column c, rows r < c (Liu's etree)
        std::vector<int> parent(n, -1), anc(n, -1);
        {
            std::vector<i64> cnt(n + 1, 0);
            for (int j = 0; j < n; ++j)
                for (i64 k = indptr[j]; k < indptr[j + 1]; ++k) {
                    int a = inv0[indices[k]], b = inv0[j];
                    if (a < b) cnt[b + 1]++;
                }
            for (int j = 0; j < n; ++j) cnt[j + 1] += cnt[j];
            std::vector<int> up(cnt[n]);
            std::vector<i64> pos(cnt.begin(), cnt.end() - 1);
            for (int j = 0; j < n; ++j)
                for (i64 k = indptr[j]; k < indptr[j + 1]; ++k) {
                    int a = inv0[indices[k]], b = inv0[j];
                    if (a < b) up[pos[b]++] = a;
                }
            for (int c = 0; c < n; ++c)
                for (i64 k = cnt[c]; k < cnt[c + 1]; ++k) {
                    int i = up[k];
                    while (i != -1 && i < c) {
                        int nx = anc[i];
                        anc[i] = c;
                        if (nx == -1) parent[i] = c;
                        i = nx;
                    }
                }
        }
        // postorder of the elimination forest
        std::vector<int> head(n, -1), next(n, -1), post;
        post.reserve(n);
        for (int j = n - 1; j >= 0; --j)
            if (parent[j] != -1) { next[j] = head[parent[j]]; head[parent[j]] = j; }
        {
            std::vector<int> stack;
            for (int r = 0; r < n; ++r) {
                if (parent[r] != -1) continue;
                stack.push_back(r);
                while (!stack.empty()) {
                    int p = stack.back();
                    int c = head[p];
                    if (c == -1) { stack.pop_back(); post.push_back(p); }
                    else { head[p] = next[c]; stack.push_back(c); }
                }
            }
        }
        std::vector<int> newlab(n);
        for (int q = 0; q < n; ++q) newlab[post[q]] = q;
        perm.resize(n);
        std::vector<int> inv(n);
        for (int q = 0; q < n; ++q) { perm[q] = p0[post[q]]; inv[perm[q]] = q; }
        std::vector<int> par(n, -1);
        for (int j = 0; j < n; ++j) if (parent[j] != -1) par[newlab[j]] = newlab[parent[j]];

        // lower pattern in the final labels, with the index of each input value
        std::vector<i64> lp(n + 1, 0);
        for (int j = 0; j < n; ++j)
            for (i64 k = indptr[j]; k < indptr[j + 1]; ++k)
                if (inv[indices[k]] >= inv[j]) lp[inv[j] + 1]++;
        for (int j = 0; j < n; ++j) lp[j + 1] += lp[j];
        std::vector<int> li(lp[n]);
        std::vector<i64> lsrc(lp[n]);
        {
            std::vector<i64> pos(lp.begin(), lp.end() - 1);
            for (int j = 0; j < n; ++j)
                for (i64 k = indptr[j]; k < indptr[j + 1]; ++k) {
                    int a = inv[indices[k]], b = inv[j];
                    if (a >= b) { li[pos[b]] = a; lsrc[pos[b]++] = k; }
                }
        }
        // column structures (with the diagonal) from A and the children
        std::vector<int> nch(n, 0);
        for (int j = 0; j < n; ++j) if (par[j] != -1) nch[par[j]]++;
        std::vector<std::vector<int>> cs(n);
        std::vector<int> mark(n, -1), cc(n);
        std::vector<int> chead(n, -1), cnext(n, -1);
        for (int j = n - 1; j >= 0; --j)
            if (par[j] != -1) { cnext[j] = chead[par[j]]; chead[par[j]] = j; }
        for (int j = 0; j < n; ++j) {
            std::vector<int> &s = cs[j];
            s.push_back(j);
            mark[j] = j;
            for (i64 k = lp[j]; k < lp[j + 1]; ++k)
                if (mark[li[k]] != j) { mark[li[k]] = j; s.push_back(li[k]); }
            for (int c = chead[j]; c != -1; c = cnext[c])
                for (int r : cs[c])
                    if (r > j && mark[r] != j) { mark[r] = j; s.push_back(r); }
            cc[j] = int(s.size());
            // a child's structure is kept only if it starts a fundamental supernode
            for (int c = chead[j]; c != -1; c = cnext[c])
                if (c > 0 && par[c - 1] == c && nch[c] == 1 && cc[c - 1] == cc[c] + 1)
                    std::vector<int>().swap(cs[c]);
        }
        // fundamental supernodes: j joins j-1 when j-1's only parent is j, j has one
        // child and the structures nest
        std::vector<int> ffirst;  // fundamental supernode start columns
        std::vector<int> fsn(n);
        for (int j = 0; j < n; ++j) {
            bool join = j > 0 && par[j - 1] == j && nch[j] == 1 && cc[j - 1] == cc[j] + 1;
            if (!join) ffirst.push_back(j);
            fsn[j] = int(ffirst.size()) - 1;
        }
        int nf = int(ffirst.size());
        ffirst.push_back(n);
        // relaxed amalgamation: merge a supernode into its parent when it is the parent's
        // last child (contiguous columns) and few explicit zeros are added
        std::vector<int> fpar(nf, -1), rep(nf), ffst(nf), fnc(nf), nr(nf);
        std::vector<double> fnz(nf, 0.0);
        std::vector<char> alive(nf, 1);
        for (int f = 0; f < nf; ++f) {
            int l = ffirst[f + 1] - 1;
            fpar[f] = par[l] == -1 ? -1 : fsn[par[l]];
            rep[f] = f;
            ffst[f] = ffirst[f];
            fnc[f] = ffirst[f + 1] - ffirst[f];
            nr[f] = cc[ffirst[f]] - fnc[f];  // |R'|
            for (int j = ffirst[f]; j <= l; ++j) fnz[f] += cc[j];
        }
        auto find = [&](int f) {
            int r = f;
            while (rep[r] != r) r = rep[r];
            while (rep[f] != r) { int nx = rep[f]; rep[f] = r; f = nx; }
            return r;
        };
        for (int f = 0; f < nf; ++f) {
            if (fpar[f] == -1) continue;
            int p = find(fpar[f]);
            int lastf = ffirst[f + 1] - 1;
            if (lastf + 1 != ffst[p]) continue;
            double ncol = double(fnc[f]) + fnc[p];
            double stored = ncol * (ncol + 1) / 2 + ncol * nr[p];
            double zeros = stored - (fnz[f] + fnz[p]);
            double frac = zeros / stored;
            bool merge = ncol <= 4 || (ncol <= 16 && frac < 0.8) || (ncol <= 48 && frac < 0.1) || frac < 0.05;
            if (!merge) continue;
            rep[f] = p;
            alive[f] = 0;
            ffst[p] = ffst[f];
            fnc[p] += fnc[f];
            fnz[p] += fnz[f];
        }
        // final supernodes in column order
        std::vector<int> sid(nf, -1);
        for (int f = 0; f < nf; ++f)
            if (alive[f]) { sid[f] = ns++; first.push_back(ffst[f]); }
        first.push_back(n);
        rptr.assign(ns + 1, 0);
        sparent.assign(ns, -1);
        nchild.assign(ns, 0);
        for (int f = 0; f < nf; ++f) {
            if (!alive[f]) continue;
            int J = sid[f];
            const std::vector<int> &s = cs[ffirst[f]];  // the top fundamental node's structure
            int top_nc = ffirst[f + 1] - ffirst[f];
            rptr[J + 1] = rptr[J] + fnc[f] + (i64(s.size()) - top_nc);
            if (fpar[f] != -1) sparent[J] = sid[find(fpar[f])];
        }
        rows.resize(rptr[ns]);
        for (int f = 0; f < nf; ++f) {
            if (!alive[f]) continue;
            int J = sid[f];
            i64 o = rptr[J];
            for (int j = first[J]; j < first[J + 1]; ++j) rows[o++] = j;
            std::vector<int> rp;
            for (int r : cs[ffirst[f]]) if (r >= ffirst[f + 1]) rp.push_back(r);
            std::sort(rp.begin(), rp.end());
            for (int r : rp) rows[o++] = r;
        }
        cs.clear();
        cs.shrink_to_fit();
        for (int J = 0; J < ns; ++J) if (sparent[J] != -1) nchild[sparent[J]]++;
        // panels, relative indices, assembly maps
        lptr.assign(ns + 1, 0);
        relptr.assign(ns + 1, 0);
        for (int J = 0; J < ns; ++J) {
            lptr[J + 1] = lptr[J] + i64(m(J)) * nc(J);
            relptr[J + 1] = relptr[J] + (m(J) - nc(J));
            double a = nc(J), b = m(J) - nc(J);
            flops += a * a * a / 3 + a * a * b + a * b * b;
        }
        nnz_L = lptr[ns];
        rel.resize(relptr[ns]);
        std::vector<int> loc(n, -1);
        aptr.assign(ns + 1, 0);
        asrc.resize(lp[n]);
        adst.resize(lp[n]);
        amirror.resize(lp[n]);
        i64 na = 0;
        for (int J = 0; J < ns; ++J) {
            int mJ = m(J);
            for (int a = 0; a < mJ; ++a) loc[rows[rptr[J] + a]] = a;
            for (int j = first[J]; j < first[J + 1]; ++j)
                for (i64 k = lp[j]; k < lp[j + 1]; ++k) {
                    asrc[na] = lsrc[k];
                    amirror[na] = li[k] == j ? -1 : mirror_of(indptr, indices, perm[li[k]], perm[j]);
                    adst[na++] = loc[li[k]] + i64(j - first[J]) * mJ;
                }
            aptr[J + 1] = na;
            for (int a = 0; a < mJ; ++a) loc[rows[rptr[J] + a]] = -1;
        }
        for (int J = 0; J < ns; ++J) {
            int P = sparent[J];
            if (P == -1) {
                if (m(J) != nc(J)) throw std::logic_error("root supernode with off-diagonal rows");
                continue;
            }
            for (int a = 0; a < m(P); ++a) loc[rows[rptr[P] + a]] = a;
            for (int a = nc(J); a < m(J); ++a) {
                int pos = loc[rows[rptr[J] + a]];
                if (pos < 0) throw std::logic_error("supernode row not in its parent");
                rel[relptr[J] + a - nc(J)] = pos;
            }
            for (int a = 0; a < m(P); ++a) loc[rows[rptr[P] + a]] = -1;
        }
    }
};

// ------------------------------------------------------------------------- numeric
template <class T>
struct Factor {
    std::shared_ptr<Symbolic> S;
    std::vector<T> Lx;  // panels: column-major m x nc, unit lower diagonal block
    std::vector<T> D;   // pivots, internal order

    Factor(std::shared_ptr<Symbolic> sym, const T *vals) : S(std::move(sym)) {
        std::exception_ptr err;
        numeric(vals, err);
        if (err) std::rethrow_exception(err);
    }

    // the numeric factorization, in the instruction set chosen by isa::avx2()
    ISA_AVX2 void numeric_avx2(const T *vals, std::exception_ptr &err) { numeric_body(vals, err); }
    ISA_BASELINE void numeric_baseline(const T *vals, std::exception_ptr &err) { numeric_body(vals, err); }
    void numeric(const T *vals, std::exception_ptr &err) {
        if (isa::avx2()) numeric_avx2(vals, err); else numeric_baseline(vals, err);
    }
    ISA_BODY void numeric_body(const T *vals, std::exception_ptr &err) {
        try {
        const Symbolic &s = *S;
        Lx.assign(s.nnz_L, T(0));
        D.assign(s.n, T(0));
        std::vector<std::vector<T>> stack;  // update matrices (lower, column-major)
        std::vector<int> stack_id;          // the supernode each update comes from
        std::vector<T> F, W;
        for (int J = 0; J < s.ns; ++J) {
            const int m = s.m(J), nc = s.nc(J), mr = m - nc;
            F.assign(size_t(m) * m, T(0));
            for (i64 k = s.aptr[J]; k < s.aptr[J + 1]; ++k) F[s.adst[k]] += vals[s.asrc[k]];
            // extend-add the children's updates (on top of the stack, in postorder)
            for (int c = 0; c < s.nchild[J]; ++c) {
                // in postorder, J's children's updates are the top of the stack
                std::vector<T> U = std::move(stack.back());
                const int C = stack_id.back();
                stack.pop_back();
                stack_id.pop_back();
                const int mc = s.m(C) - s.nc(C);
                const int *r = &s.rel[s.relptr[C]];
                for (int b = 0; b < mc; ++b) {
                    T *Fc = &F[size_t(r[b]) * m];
                    const T *Uc = &U[size_t(b) * mc];
                    for (int a = b; a < mc; ++a) Fc[r[a]] += Uc[a];
                }
            }
            T *Dj = &D[s.first[J]];
            if (blas::use(s.factor_work(J))) {
                front_blas(F.data(), m, nc, Dj, s.first[J], W);
                if (mr > 0) {
                    std::vector<T> U(size_t(mr) * mr);
                    for (int j = 0; j < mr; ++j)
                        std::copy(&F[size_t(nc + j) * m + nc + j], &F[size_t(nc + j) * m + m], &U[size_t(j) * mr + j]);
                    stack.push_back(std::move(U));
                    stack_id.push_back(J);
                }
                std::copy(F.begin(), F.begin() + size_t(m) * nc, Lx.begin() + s.lptr[J]);
                continue;
            }
            // dense LDL^T of the first nc columns
            for (int k = 0; k < nc; ++k) {
                T d = F[size_t(k) * m + k];
                if (d == T(0))
                    throw std::runtime_error("zero pivot in LDL^T at column " + std::to_string(s.first[J] + k));
                Dj[k] = d;
                T *Fk = &F[size_t(k) * m];
                T dinv = T(1) / d;
                for (int j = k + 1; j < nc; ++j) {
                    T sc = Fk[j] * dinv;
                    T *Fj = &F[size_t(j) * m];
                    for (int i = j; i < m; ++i) Fj[i] -= Fk[i] * sc;
                }
                for (int i = k + 1; i < m; ++i) Fk[i] *= dinv;
            }
            // trailing update U = F22 - L21 D L21^T (lower)
            if (mr > 0) {
                W.assign(size_t(mr) * nc, T(0));
                for (int k = 0; k < nc; ++k)
                    for (int j = 0; j < mr; ++j) W[size_t(k) * mr + j] = F[size_t(k) * m + nc + j] * Dj[k];
                std::vector<T> U(size_t(mr) * mr);
                for (int j = 0; j < mr; ++j) {
                    T *Uj = &U[size_t(j) * mr];
                    const T *Fj = &F[size_t(nc + j) * m + nc];
                    for (int i = j; i < mr; ++i) Uj[i] = Fj[i];
                    int k = 0;
                    for (; k + 4 <= nc; k += 4) {
                        const T w0 = W[size_t(k) * mr + j], w1 = W[size_t(k + 1) * mr + j];
                        const T w2 = W[size_t(k + 2) * mr + j], w3 = W[size_t(k + 3) * mr + j];
                        const T *L0 = &F[size_t(k) * m + nc], *L1 = &F[size_t(k + 1) * m + nc];
                        const T *L2 = &F[size_t(k + 2) * m + nc], *L3 = &F[size_t(k + 3) * m + nc];
                        for (int i = j; i < mr; ++i) Uj[i] -= L0[i] * w0 + L1[i] * w1 + L2[i] * w2 + L3[i] * w3;
                    }
                    for (; k < nc; ++k) {
                        const T w = W[size_t(k) * mr + j];
                        const T *Lk = &F[size_t(k) * m + nc];
                        for (int i = j; i < mr; ++i) Uj[i] -= Lk[i] * w;
                    }
                }
                stack.push_back(std::move(U));
                stack_id.push_back(J);
            }
            std::copy(F.begin(), F.begin() + size_t(m) * nc, Lx.begin() + s.lptr[J]);
        }
            } catch (...) {   // no exception may leave a run-time dispatched clone
            err = std::current_exception();
        }
    }

    // The front F (m x m, column-major, lower part) of a large supernode with BLAS: LDL^T of
    // its first nc columns by blocks of NB (each block's columns by the loops, the rest of
    // the panel by one gemm), then the trailing update F22 -= L21 D L21^T by column blocks
    // of the lower triangle. Leaves L in F[:, :nc] (its strictly upper part zeroed), D in
    // Dj and the update in F22's lower triangle.
    static void front_blas(T *F, const int m, const int nc, T *Dj, const int col0, std::vector<T> &W) {
        constexpr int NB = blas::front_nb, CB = blas::front_cb;
        const int mr = m - nc;
        for (int kb = 0; kb < nc; kb += NB) {
            const int be = std::min(nc, kb + NB);
            for (int k = kb; k < be; ++k) {
                const T d = F[size_t(k) * m + k];
                if (d == T(0))
                    throw std::runtime_error("zero pivot in LDL^T at column " + std::to_string(col0 + k));
                Dj[k] = d;
                T *Fk = &F[size_t(k) * m];
                const T dinv = T(1) / d;
                for (int j = k + 1; j < be; ++j) {
                    const T sc = Fk[j] * dinv;
                    T *Fj = &F[size_t(j) * m];
                    for (int i = j; i < m; ++i) Fj[i] -= Fk[i] * sc;
                }
                for (int i = k + 1; i < m; ++i) Fk[i] *= dinv;
            }
            if (be < nc) {   // F[be:m, be:nc] -= L[be:m, kb:be] (L[be:nc, kb:be] D)^T
                const int w = be - kb, cols = nc - be;
                W.resize(size_t(cols) * w);
                for (int c = 0; c < w; ++c)
                    for (int j = 0; j < cols; ++j) W[size_t(c) * cols + j] = F[size_t(kb + c) * m + be + j] * Dj[kb + c];
                blas::gemm<T>('N', 'T', m - be, cols, w, T(-1), &F[size_t(kb) * m + be], m, W.data(), cols, T(1),
                              &F[size_t(be) * m + be], m);
            }
        }
        for (int j = 1; j < nc; ++j) std::fill(&F[size_t(j) * m], &F[size_t(j) * m + j], T(0));
        if (mr == 0) return;
        W.resize(size_t(mr) * nc);                 // W = L21 D (mr x nc)
        for (int k = 0; k < nc; ++k)
            for (int j = 0; j < mr; ++j) W[size_t(k) * mr + j] = F[size_t(k) * m + nc + j] * Dj[k];
        for (int j0 = 0; j0 < mr; j0 += CB) {       // columns j0.. of F22, rows j0..mr
            const int jw = std::min(CB, mr - j0);
            blas::gemm<T>('N', 'T', mr - j0, jw, nc, T(-1), &F[nc + j0], m, &W[j0], mr, T(1),
                          &F[size_t(nc + j0) * m + nc + j0], m);
        }
    }

    // X <- A^-1 X for X (n x k, row-major) in internal order: all k columns together.
    // With lo/hi (per supernode), the forward substitution at supernode J touches only the
    // columns [lo[J], hi[J]): the others are known to be zero there (see inverse_columns).
    void solve_internal(T *x, const size_t k, const int *lo = nullptr, const int *hi = nullptr) const {
        std::exception_ptr err;
        if (k == 1) solve_block<1>(x, 1, lo, hi, err);     // the compiler unrolls the one-column case
        else solve_block<0>(x, k, lo, hi, err);
        if (err) std::rethrow_exception(err);
    }

    // Columns idx of A^-1 (original labels), as X (n x k, row-major, internal order).
    // Column c's right-hand side is the unit vector at internal row q_c, so its forward
    // substitution is nonzero only on the supernodes whose subtree holds q_c. Subtrees are
    // contiguous column ranges in postorder, so with the columns sorted by q the columns
    // alive at supernode J are one contiguous range.
    std::vector<T> inverse_columns_internal(const std::vector<int> &q_sorted) const {
        const Symbolic &s = *S;
        const size_t k = q_sorted.size();
        std::vector<T> x(size_t(s.n) * k, T(0));
        for (size_t c = 0; c < k; ++c) x[size_t(q_sorted[c]) * k + c] = T(1);
        std::vector<int> low(s.first.begin(), s.first.end() - 1);   // first column of J's subtree
        for (int J = 0; J < s.ns; ++J)
            if (s.sparent[J] != -1) low[s.sparent[J]] = std::min(low[s.sparent[J]], low[J]);
        std::vector<int> lo(s.ns), hi(s.ns);
        for (int J = 0; J < s.ns; ++J) {
            lo[J] = int(std::lower_bound(q_sorted.begin(), q_sorted.end(), low[J]) - q_sorted.begin());
            hi[J] = int(std::lower_bound(q_sorted.begin(), q_sorted.end(), s.first[J + 1]) - q_sorted.begin());
        }
        solve_internal(x.data(), k, lo.data(), hi.data());
        return x;
    }

    // Supernode by supernode: the dense diagonal block first (its rows are f..f+nc-1), then
    // the rows below it, each row's update summed over the block's columns in a small
    // buffer and applied once (the block's nc rows of X stay in cache; the scattered rows
    // of X are touched once per supernode, not once per column).
    template <size_t K>
    ISA_AVX2 void solve_block_avx2(T *x, size_t k, const int *lo, const int *hi, std::exception_ptr &err) const {
        solve_block_body<K>(x, k, lo, hi, err);
    }
    template <size_t K>
    ISA_BASELINE void solve_block_baseline(T *x, size_t k, const int *lo, const int *hi, std::exception_ptr &err) const {
        solve_block_body<K>(x, k, lo, hi, err);
    }
    template <size_t K>
    void solve_block(T *x, size_t k, const int *lo, const int *hi, std::exception_ptr &err) const {
        if (isa::avx2()) solve_block_avx2<K>(x, k, lo, hi, err); else solve_block_baseline<K>(x, k, lo, hi, err);
    }
    template <size_t K>
    ISA_BODY void solve_block_body(T *x, size_t k_dyn, const int *lo, const int *hi, std::exception_ptr &err) const {
        try {
        const size_t k = K ? K : k_dyn;
        const Symbolic &s = *S;
        std::vector<T> buf(k), G;
        for (int J = 0; J < s.ns; ++J) {
            const int m = s.m(J), nc = s.nc(J), f = s.first[J];
            const size_t c0 = lo ? size_t(lo[J]) : 0, c1 = hi ? size_t(hi[J]) : k;
            if (c0 >= c1) continue;
            const T *P = &Lx[s.lptr[J]];
            const int *r = &s.rows[s.rptr[J]];
            const int kk = int(c1 - c0), mr = m - nc;
            if (blas::use(s.solve_work(J, kk))) {
                // X_J^T <- X_J^T L11^-T, then G = (L21 X_J)^T scattered into the rows below
                T *XJ = x + size_t(f) * k + c0;
                blas::trsm<T>('R', 'L', 'T', 'U', kk, nc, T(1), P, m, XJ, int(k));
                G.resize(size_t(kk) * mr);
                blas::gemm<T>('N', 'T', kk, mr, nc, T(1), XJ, int(k), P + nc, m, T(0), G.data(), kk);
                for (int i = 0; i < mr; ++i) {
                    T *xi = x + size_t(r[nc + i]) * k + c0;
                    const T *gi = &G[size_t(i) * kk];
                    for (int c = 0; c < kk; ++c) xi[c] -= gi[c];
                }
                continue;
            }
            for (int kc = 0; kc < nc; ++kc) {
                const T *xk = x + size_t(f + kc) * k;
                const T *Pk = P + size_t(kc) * m;
                for (int i = kc + 1; i < nc; ++i) {
                    const T l = Pk[i];
                    T *xi = x + size_t(f + i) * k;
                    for (size_t c = c0; c < c1; ++c) xi[c] -= l * xk[c];
                }
            }
            for (int i = nc; i < m; ++i) {
                std::fill(buf.begin() + c0, buf.begin() + c1, T(0));
                for (int kc = 0; kc < nc; ++kc) {
                    const T l = P[size_t(kc) * m + i];
                    const T *xk = x + size_t(f + kc) * k;
                    for (size_t c = c0; c < c1; ++c) buf[c] += l * xk[c];
                }
                T *xi = x + size_t(r[i]) * k;
                for (size_t c = c0; c < c1; ++c) xi[c] -= buf[c];
            }
        }
        for (int i = 0; i < s.n; ++i) {
            const T dinv = T(1) / D[i];
            for (size_t c = 0; c < k; ++c) x[size_t(i) * k + c] *= dinv;
        }
        for (int J = s.ns - 1; J >= 0; --J) {
            const int m = s.m(J), nc = s.nc(J), f = s.first[J];
            const T *P = &Lx[s.lptr[J]];
            const int *r = &s.rows[s.rptr[J]];
            if (blas::use(s.solve_work(J, double(k)))) {
                // X_J^T -= X_R^T L21 (the rows below, gathered), then X_J^T <- X_J^T L11^-1
                const int mr = m - nc;
                T *XJ = x + size_t(f) * k;
                G.resize(size_t(k) * mr);
                for (int i = 0; i < mr; ++i) std::copy(x + size_t(r[nc + i]) * k, x + size_t(r[nc + i]) * k + k, &G[size_t(i) * k]);
                blas::gemm<T>('N', 'N', int(k), nc, mr, T(-1), G.data(), int(k), P + nc, m, T(1), XJ, int(k));
                blas::trsm<T>('R', 'L', 'N', 'U', int(k), nc, T(1), P, m, XJ, int(k));
                continue;
            }
            for (int i = nc; i < m; ++i) {          // rows below the block: final already
                const T *xi = x + size_t(r[i]) * k;
                for (int kc = 0; kc < nc; ++kc) {
                    const T l = P[size_t(kc) * m + i];
                    T *xk = x + size_t(f + kc) * k;
                    for (size_t c = 0; c < k; ++c) xk[c] -= l * xi[c];
                }
            }
            for (int kc = nc - 1; kc >= 0; --kc) {
                const T *Pk = P + size_t(kc) * m;
                T *xk = x + size_t(f + kc) * k;
                for (int i = kc + 1; i < nc; ++i) {
                    const T l = Pk[i];
                    const T *xi = x + size_t(f + i) * k;
                    for (size_t c = 0; c < k; ++c) xk[c] -= l * xi[c];
                }
            }
        }
            } catch (...) {
            err = std::current_exception();
        }
    }

    // diag(A^-1), internal order: selected inversion, root first; with pattern (nnz_in
    // entries) also A^-1 on the input pattern, input order
    std::vector<T> inverse_diagonal(T *pattern = nullptr) const {
        std::vector<T> out;
        std::exception_ptr err;
        inverse_diagonal_kernel(out, pattern, err);
        if (err) std::rethrow_exception(err);
        return out;
    }

    // selected inversion: diag(A^-1) in out (internal order) and, when pattern is not null,
    // the entries of A^-1 on the input pattern (both triangles, input order) in pattern
    ISA_AVX2 void inverse_diagonal_avx2(std::vector<T> &out, T *pattern, std::exception_ptr &err) const {
        inverse_diagonal_body(out, pattern, err);
    }
    ISA_BASELINE void inverse_diagonal_baseline(std::vector<T> &out, T *pattern, std::exception_ptr &err) const {
        inverse_diagonal_body(out, pattern, err);
    }
    void inverse_diagonal_kernel(std::vector<T> &out, T *pattern, std::exception_ptr &err) const {
        if (isa::avx2()) inverse_diagonal_avx2(out, pattern, err); else inverse_diagonal_baseline(out, pattern, err);
    }
    ISA_BODY void inverse_diagonal_body(std::vector<T> &out, T *pattern, std::exception_ptr &err) const {
        try {
        const Symbolic &s = *S;
        std::vector<T> diag(s.n);
        std::vector<std::vector<T>> Z(s.ns);  // full m x m blocks of A^-1, alive while needed
        std::vector<int> pending(s.ns, 0);
        std::vector<T> Y, Linv, LinvD, dinv_(s.n);
        for (int J = s.ns - 1; J >= 0; --J) {
            const int m = s.m(J), nc = s.nc(J), mr = m - nc, f = s.first[J];
            const T *P = &Lx[s.lptr[J]];
            std::vector<T> &ZJ = Z[J];
            ZJ.assign(size_t(m) * m, T(0));
            const int Par = s.sparent[J];
            if (Par != -1) {
                const std::vector<T> &ZP = Z[Par];
                const int mp = s.m(Par);
                const int *r = &s.rel[s.relptr[J]];
                for (int b = 0; b < mr; ++b) {
                    const T *src = &ZP[size_t(r[b]) * mp];
                    T *dst = &ZJ[size_t(nc + b) * m + nc];
                    for (int a = 0; a < mr; ++a) dst[a] = src[r[a]];
                }
                if (--pending[Par] == 0) std::vector<T>().swap(Z[Par]);
            }
            if (blas::use(s.inverse_work(J))) {
                // Y = L21 L11^-1; Z21 = -Zhat Y; Z11 = L11^-T D^-1 L11^-1 - Z21^T Y
                Y.resize(size_t(mr) * nc);
                for (int k = 0; k < nc; ++k) std::copy(P + size_t(k) * m + nc, P + size_t(k) * m + m, &Y[size_t(k) * mr]);
                blas::trsm<T>('R', 'L', 'N', 'U', mr, nc, T(1), P, m, Y.data(), mr);
                blas::gemm<T>('N', 'N', mr, nc, mr, T(-1), &ZJ[size_t(nc) * m + nc], m, Y.data(), mr, T(0), &ZJ[nc], m);
                Linv.assign(size_t(nc) * nc, T(0));
                for (int k = 0; k < nc; ++k) Linv[size_t(k) * nc + k] = T(1);
                blas::trsm<T>('L', 'L', 'N', 'U', nc, nc, T(1), P, m, Linv.data(), nc);
                LinvD.resize(size_t(nc) * nc);
                for (int b = 0; b < nc; ++b)
                    for (int i = 0; i < nc; ++i) LinvD[size_t(b) * nc + i] = Linv[size_t(b) * nc + i] / D[f + i];
                blas::trmm<T>('L', 'L', 'T', 'U', nc, nc, T(1), Linv.data(), nc, LinvD.data(), nc);
                for (int b = 0; b < nc; ++b) std::copy(&LinvD[size_t(b) * nc], &LinvD[size_t(b) * nc + nc], &ZJ[size_t(b) * m]);
                blas::gemm<T>('T', 'N', nc, nc, mr, T(-1), &ZJ[nc], m, Y.data(), mr, T(1), ZJ.data(), m);
                for (int b = 0; b < nc; ++b)            // symmetric: the lower triangle mirrored
                    for (int a = b + 1; a < nc; ++a) ZJ[size_t(a) * m + b] = ZJ[size_t(b) * m + a];
            } else {
            // Y = L21 L11^-1 (mr x nc)
            Y.assign(size_t(mr) * nc, T(0));
            for (int k = 0; k < nc; ++k)
                for (int i = 0; i < mr; ++i) Y[size_t(k) * mr + i] = P[size_t(k) * m + nc + i];
            for (int k = nc - 1; k >= 0; --k)
                for (int j = k + 1; j < nc; ++j) {
                    const T l = P[size_t(k) * m + j];
                    if (l == T(0)) continue;
                    T *Yk = &Y[size_t(k) * mr];
                    const T *Yj = &Y[size_t(j) * mr];
                    for (int i = 0; i < mr; ++i) Yk[i] -= Yj[i] * l;
                }
            // Z21 = -Zhat Y, stored in ZJ rows nc.., columns 0..nc-1
            for (int k = 0; k < nc; ++k) {
                T *Zk = &ZJ[size_t(k) * m + nc];
                const T *Yk = &Y[size_t(k) * mr];
                int j = 0;
                for (; j + 4 <= mr; j += 4) {
                    const T y0 = Yk[j], y1 = Yk[j + 1], y2 = Yk[j + 2], y3 = Yk[j + 3];
                    const T *A0 = &ZJ[size_t(nc + j) * m + nc], *A1 = A0 + m, *A2 = A1 + m, *A3 = A2 + m;
                    for (int i = 0; i < mr; ++i) Zk[i] -= A0[i] * y0 + A1[i] * y1 + A2[i] * y2 + A3[i] * y3;
                }
                for (; j < mr; ++j) {
                    const T y = Yk[j];
                    const T *A = &ZJ[size_t(nc + j) * m + nc];
                    for (int i = 0; i < mr; ++i) Zk[i] -= A[i] * y;
                }
            }
            // L11^-1 (unit lower), then Z11 = L11^-T D^-1 L11^-1 - Z21^T Y
            Linv.assign(size_t(nc) * nc, T(0));
            for (int k = 0; k < nc; ++k) {
                T *c = &Linv[size_t(k) * nc];
                c[k] = T(1);
                for (int j = k; j < nc; ++j) {
                    const T cj = c[j];
                    if (cj == T(0)) continue;
                    const T *Pj = P + size_t(j) * m;
                    for (int i = j + 1; i < nc; ++i) c[i] -= Pj[i] * cj;
                }
            }
            // LinvD = D^-1 L11^-1 (rows scaled), so that Z11 needs no division inside the loop
            LinvD.resize(size_t(nc) * nc);
            for (int i = 0; i < nc; ++i) dinv_[i] = T(1) / D[f + i];
            for (int b = 0; b < nc; ++b)
                for (int i = 0; i < nc; ++i) LinvD[size_t(b) * nc + i] = Linv[size_t(b) * nc + i] * dinv_[i];
            for (int b = 0; b < nc; ++b)
                for (int a = b; a < nc; ++a) {
                    T acc = T(0);
                    const T *La = &Linv[size_t(a) * nc], *Wb = &LinvD[size_t(b) * nc];
                    for (int i = a; i < nc; ++i) acc += La[i] * Wb[i];   // Linv lower: i >= max(a, b) = a
                    const T *Za = &ZJ[size_t(a) * m + nc];
                    const T *Yb = &Y[size_t(b) * mr];
                    for (int i = 0; i < mr; ++i) acc -= Za[i] * Yb[i];
                    ZJ[size_t(b) * m + a] = acc;
                    ZJ[size_t(a) * m + b] = acc;
                }
            }
            // the upper-right block Z12 = Z21^T
            for (int k = 0; k < nc; ++k)
                for (int i = 0; i < mr; ++i) ZJ[size_t(nc + i) * m + k] = ZJ[size_t(k) * m + nc + i];
            for (int k = 0; k < nc; ++k) diag[f + k] = ZJ[size_t(k) * m + k];
            if (pattern)   // the input's entries in J's columns (and their mirrors) lie in Z_J
                for (i64 k = s.aptr[J]; k < s.aptr[J + 1]; ++k) {
                    const T v = ZJ[s.adst[k]];
                    pattern[s.asrc[k]] = v;
                    if (s.amirror[k] >= 0) pattern[s.amirror[k]] = v;
                }
            pending[J] = s.nchild[J];
            if (pending[J] == 0) std::vector<T>().swap(ZJ);
        }
        out = std::move(diag);
            } catch (...) {
            err = std::current_exception();
        }
    }
};

template <class T>
using In1 = nb::ndarray<const T, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
template <class T>
using Out = nb::ndarray<nb::numpy, T>;

template <class T>
Out<T> to_numpy(std::vector<T> &&v, std::vector<size_t> shape) {
    auto *buf = new std::vector<T>(std::move(v));
    nb::capsule owner(buf, [](void *p) noexcept { delete static_cast<std::vector<T> *>(p); });
    return Out<T>(buf->data(), shape.size(), shape.data(), owner);
}

// ------------------------------------------------------------------------- Chebyshev series
// Terms 2..K of the Chebyshev recurrence of spectral_igl.approx.uniformization.chebyshev_blocks
// on a block-diagonal CSR matrix P (n x n, its factor -2/sigma taken in) and row-major blocks
// of w columns. Term k runs on the blocks within the leading rows[k] rows:
//     t_k = P t_{k-1} - t_{k-2} (in t_{k-2}'s place), W += C[b, k] t_k (b the row's block).
// Every entry is rounded exactly as the numpy form (q = P @ t1, summed in stored order from
// 0; q - t0; W += coef * t) rounds it, so the two agree bit for bit and the series' proved
// rounding bound holds for both. No fused multiply-add: the AVX2 clone is compiled without
// FMA, and the baseline has none. The blocks are independent, so each runs all its terms
// while its rows are in cache.
template <int WC, class I>
ISA_BODY void chebyshev_block(int64_t b, int K, int w, const I *ip, const I *ix, const double *px, const int64_t *off,
                              const double *C, const int64_t *rows, double *t1, double *t0, double *W) {
    const int width = WC > 0 ? WC : w;
    double qbuf[WC > 0 ? WC : 1];
    std::vector<double> qvec(WC > 0 ? 0 : size_t(width));
    double *q = WC > 0 ? qbuf : qvec.data();
    const int64_t lo = off[b], hi = off[b + 1];
    for (int k = 2; k <= K && rows[k] >= hi; ++k) {
        const double ck = C[b * (K + 1) + k];
        for (int64_t i = lo; i < hi; ++i) {
            for (int c = 0; c < width; ++c) q[c] = 0.0;
            for (I p = ip[i]; p < ip[i + 1]; ++p) {
                const double a = px[p];
                const double *x = t1 + int64_t(ix[p]) * width;
                for (int c = 0; c < width; ++c) q[c] += a * x[c];
            }
            double *y = t0 + i * width, *acc = W + i * width;
            for (int c = 0; c < width; ++c) {
                const double t = q[c] - y[c];
                y[c] = t;
                acc[c] += ck * t;
            }
        }
        std::swap(t0, t1);
    }
}

// The Poisson (uniformization) series of spectral_igl.approx.uniformization.uniformize_blocks
// on the same block-diagonal P: for block b and terms k = 1..K (while rows[k] covers the
// block), q_k = (P q_{k-1}) * (lam[b] / k) and W += q_k, with q_0 = W's block on entry
// (scaled by the caller); rounded as the numpy form (q = P @ q; q *= lam / k; W += q) is.
// q and s are scratch rows of the block's size.
template <int WC, class I>
ISA_BODY void poisson_block(int64_t b, int K, int w, const I *ip, const I *ix, const double *px, const int64_t *off,
                            const double *lam, const int64_t *rows, double *q, double *s, double *W) {
    const int width = WC > 0 ? WC : w;
    const int64_t lo = off[b], hi = off[b + 1];
    for (int64_t i = lo; i < hi; ++i)
        for (int c = 0; c < width; ++c) q[i * width + c] = W[i * width + c];
    for (int k = 1; k <= K && rows[k] >= hi; ++k) {
        const double ck = lam[b] / double(k);
        for (int64_t i = lo; i < hi; ++i) {
            double *y = s + i * width;
            for (int c = 0; c < width; ++c) y[c] = 0.0;
            for (I p = ip[i]; p < ip[i + 1]; ++p) {
                const double a = px[p];
                const double *x = q + int64_t(ix[p]) * width;
                for (int c = 0; c < width; ++c) y[c] += a * x[c];
            }
            double *acc = W + i * width;
            for (int c = 0; c < width; ++c) {
                y[c] *= ck;
                acc[c] += y[c];
            }
        }
        std::swap(q, s);
    }
}

// The same two blocks for the common widths (WC a multiple of 4), their columns held in
// GCC's vectors of 4 doubles: each row's sums stay in registers over its entries. GCC's own
// vectorization of the loops above also runs over a row's entries (emulated gathers), which
// took 3 times as long on these blocks. Every entry is formed by the same operations in the
// same order (elementwise IEEE multiplies, adds and subtractions, no fused multiply-add), so
// both forms give the same bits; only the AVX2 clone takes these.
#if SERIES_VECTORS
typedef double series_v4 __attribute__((vector_size(32)));

ISA_BODY series_v4 series_load(const double *x) {
    series_v4 v;
    __builtin_memcpy(&v, x, sizeof v);
    return v;
}

ISA_BODY void series_store(double *x, const series_v4 &v) { __builtin_memcpy(x, &v, sizeof v); }

// q = row i of P times the block x (WC columns), in the vectors of 4 doubles: the same sums in
// the same order as the scalar loops (no fused multiply-add)
template <int WC, class I>
ISA_BODY void series_row(const I *ip, const I *ix, const double *px, int64_t i, const double *x,
                         series_v4 *q) {
    for (int v = 0; v < WC / 4; ++v) q[v] = series_v4{0.0, 0.0, 0.0, 0.0};
    for (I p = ip[i]; p < ip[i + 1]; ++p) {
        const double a = px[p];
        const series_v4 av = {a, a, a, a};
        const double *xr = x + int64_t(ix[p]) * WC;
        for (int v = 0; v < WC / 4; ++v) q[v] += av * series_load(xr + 4 * v);
    }
}

template <int WC, class I>
ISA_BODY void chebyshev_block_vec(int64_t b, int K, const I *ip, const I *ix, const double *px, const int64_t *off,
                                  const double *C, const int64_t *rows, double *t1, double *t0, double *W) {
    constexpr int NV = WC / 4;
    const int64_t lo = off[b], hi = off[b + 1];
    for (int k = 2; k <= K && rows[k] >= hi; ++k) {
        const double ck = C[b * (K + 1) + k];
        const series_v4 cv = {ck, ck, ck, ck};
        for (int64_t i = lo; i < hi; ++i) {
            series_v4 q[NV];
            series_row<WC>(ip, ix, px, i, t1, q);
            double *y = t0 + i * WC, *acc = W + i * WC;
            for (int v = 0; v < NV; ++v) {
                const series_v4 t = q[v] - series_load(y + 4 * v);
                series_store(y + 4 * v, t);
                series_store(acc + 4 * v, series_load(acc + 4 * v) + cv * t);
            }
        }
        std::swap(t0, t1);
    }
}

template <int WC, class I>
ISA_BODY void poisson_block_vec(int64_t b, int K, const I *ip, const I *ix, const double *px, const int64_t *off,
                                const double *lam, const int64_t *rows, double *q, double *s, double *W) {
    constexpr int NV = WC / 4;
    const int64_t lo = off[b], hi = off[b + 1];
    for (int64_t i = lo; i < hi; ++i)
        for (int c = 0; c < WC; ++c) q[i * WC + c] = W[i * WC + c];
    for (int k = 1; k <= K && rows[k] >= hi; ++k) {
        const double ck = lam[b] / double(k);
        const series_v4 cv = {ck, ck, ck, ck};
        for (int64_t i = lo; i < hi; ++i) {
            series_v4 y[NV];
            series_row<WC>(ip, ix, px, i, q, y);
            double *out = s + i * WC, *acc = W + i * WC;
            for (int v = 0; v < NV; ++v) {
                const series_v4 t = y[v] * cv;
                series_store(out + 4 * v, t);
                series_store(acc + 4 * v, series_load(acc + 4 * v) + t);
            }
        }
        std::swap(q, s);
    }
}
#endif

// Kind 0: the Chebyshev series' block (coef = C, u = t1, v = t0); kind 1: the Poisson
// series' (coef = lam, u = q, v = s). Threads take whole blocks from next; the width's
// common values get their own specializations.
template <int Kind, int WC, bool Vec, class I>
ISA_BODY void series_block(int64_t b, int K, int w, const I *ip, const I *ix, const double *px, const int64_t *off,
                           const double *coef, const int64_t *rows, double *u, double *v, double *W) {
#if SERIES_VECTORS
    if constexpr (Vec && WC > 0 && WC % 4 == 0) {
        if constexpr (Kind == 0) chebyshev_block_vec<WC>(b, K, ip, ix, px, off, coef, rows, u, v, W);
        else poisson_block_vec<WC>(b, K, ip, ix, px, off, coef, rows, u, v, W);
        return;
    }
#endif
    if constexpr (Kind == 0) chebyshev_block<WC>(b, K, w, ip, ix, px, off, coef, rows, u, v, W);
    else poisson_block<WC>(b, K, w, ip, ix, px, off, coef, rows, u, v, W);
}

template <int Kind, bool Vec, class I>
ISA_BODY void series_body(int64_t nblocks, int K, int w, const I *ip, const I *ix, const double *px,
                          const int64_t *off, const double *coef, const int64_t *rows, double *u, double *v, double *W) {
    for (int64_t b = 0; b < nblocks; ++b) {
        switch (w) {
        case 32: series_block<Kind, 32, Vec>(b, K, w, ip, ix, px, off, coef, rows, u, v, W); break;
        case 16: series_block<Kind, 16, Vec>(b, K, w, ip, ix, px, off, coef, rows, u, v, W); break;
        case 8: series_block<Kind, 8, Vec>(b, K, w, ip, ix, px, off, coef, rows, u, v, W); break;
        case 4: series_block<Kind, 4, Vec>(b, K, w, ip, ix, px, off, coef, rows, u, v, W); break;
        default: series_block<Kind, 0, Vec>(b, K, w, ip, ix, px, off, coef, rows, u, v, W);
        }
    }
}
template <int Kind, class I>
ISA_AVX2 void series_avx2(int64_t nblocks, int K, int w, const I *ip, const I *ix, const double *px,
                          const int64_t *off, const double *coef, const int64_t *rows, double *u, double *v, double *W) {
    series_body<Kind, true>(nblocks, K, w, ip, ix, px, off, coef, rows, u, v, W);
}
template <int Kind, class I>
ISA_BASELINE void series_baseline(int64_t nblocks, int K, int w, const I *ip, const I *ix, const double *px,
                                  const int64_t *off, const double *coef, const int64_t *rows, double *u, double *v,
                                  double *W) {
    series_body<Kind, false>(nblocks, K, w, ip, ix, px, off, coef, rows, u, v, W);
}

using Block = nb::ndarray<double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Coefs = nb::ndarray<const double, nb::ndim<2>, nb::c_contig, nb::device::cpu>;

// Checks everything the series' loops read: P (n x n CSR) block diagonal on the offsets, rows
// (K + 1 entries) block boundaries that never grow from term `first` on, the blocks of n rows
// and w columns distinct.
template <class I>
void check_series(const In1<I> &indptr, const In1<I> &indices, const In1<double> &data, const In1<int64_t> &offsets,
                  const In1<int64_t> &rows, int64_t K, int first, const std::vector<const Block *> &blocks) {
    const int64_t n = int64_t(blocks[0]->shape(0)), w = int64_t(blocks[0]->shape(1));
    const int64_t nblocks = int64_t(offsets.shape(0)) - 1;
    if (nblocks < 0) throw std::invalid_argument("offsets must have at least one entry");
    if (int64_t(rows.shape(0)) != K + 1) throw std::invalid_argument("rows must have one entry per term");
    for (const Block *B : blocks)
        if (int64_t(B->shape(0)) != n || int64_t(B->shape(1)) != w)
            throw std::invalid_argument("the dense blocks must have one shape");
    for (size_t a = 0; a < blocks.size(); ++a)
        for (size_t c = a + 1; c < blocks.size(); ++c)
            if (blocks[a]->data() == blocks[c]->data()) throw std::invalid_argument("the dense blocks must be distinct arrays");
    if (w < 1 || w > (1 << 20) || K > (1 << 24)) throw std::invalid_argument("1 to 2**20 columns, at most 2**24 terms");
    if (int64_t(indptr.shape(0)) != n + 1) throw std::invalid_argument("indptr must have n + 1 entries");
    const int64_t *off = offsets.data(), *rw = rows.data();
    if (off[0] != 0 || off[nblocks] != n) throw std::invalid_argument("offsets must run from 0 to n");
    for (int64_t b = 0; b < nblocks; ++b)
        if (off[b + 1] < off[b]) throw std::invalid_argument("offsets must not decrease");
    for (int64_t k = first; k <= K; ++k)
        if (rw[k] < 0 || rw[k] > n || (k > first && rw[k] > rw[k - 1]) ||
            !std::binary_search(off, off + nblocks + 1, rw[k]))
            throw std::invalid_argument("rows must be block boundaries that never grow");
    const I *ip = indptr.data(), *ix = indices.data();
    if (ip[0] != 0 || int64_t(ip[n]) > int64_t(indices.shape(0)) || int64_t(ip[n]) > int64_t(data.shape(0)))
        throw std::invalid_argument("indptr does not fit indices and data");
    for (int64_t b = 0; b < nblocks; ++b)
        for (int64_t i = off[b]; i < off[b + 1]; ++i) {
            if (ip[i + 1] < ip[i]) throw std::invalid_argument("indptr must not decrease");
            for (I p = ip[i]; p < ip[i + 1]; ++p)
                if (int64_t(ix[p]) < off[b] || int64_t(ix[p]) >= off[b + 1])
                    throw std::invalid_argument("indices out of range: P must be block diagonal on the offsets");
        }
}

// The series of kind Kind (series_block) without the GIL, in the CPU's clone.
template <int Kind, class I>
void run_series(int64_t nblocks, int K, int w, const I *ip, const I *ix, const double *px, const int64_t *off,
                const double *coef, const int64_t *rows, double *u, double *v, double *W) {
    nb::gil_scoped_release rel;
    if (isa::avx2()) series_avx2<Kind, I>(nblocks, K, w, ip, ix, px, off, coef, rows, u, v, W);
    else series_baseline<Kind, I>(nblocks, K, w, ip, ix, px, off, coef, rows, u, v, W);
}

template <class I>
void chebyshev_series(In1<I> indptr, In1<I> indices, In1<double> data, In1<int64_t> offsets, Coefs C,
                      In1<int64_t> rows, Block t1, Block t0, Block W) {
    const int64_t nblocks = int64_t(offsets.shape(0)) - 1, K = int64_t(C.shape(1)) - 1;
    if (int64_t(C.shape(0)) != nblocks) throw std::invalid_argument("C must have one row per block");
    check_series<I>(indptr, indices, data, offsets, rows, K, 2, {&t1, &t0, &W});
    if (K < 2) return;
    const int w = int(t1.shape(1));
    run_series<0, I>(nblocks, int(K), w, indptr.data(), indices.data(), data.data(), offsets.data(), C.data(),
                     rows.data(), t1.data(), t0.data(), W.data());
}

template <class I>
void poisson_series(In1<I> indptr, In1<I> indices, In1<double> data, In1<int64_t> offsets, In1<double> lam,
                    In1<int64_t> rows, Block q, Block s, Block W) {
    const int64_t nblocks = int64_t(offsets.shape(0)) - 1, K = int64_t(rows.shape(0)) - 1;
    if (int64_t(lam.shape(0)) != nblocks) throw std::invalid_argument("lam must have one entry per block");
    check_series<I>(indptr, indices, data, offsets, rows, K, 1, {&q, &s, &W});
    const int w = int(q.shape(1));
    run_series<1, I>(nblocks, int(K), w, indptr.data(), indices.data(), data.data(), offsets.data(),
                     lam.data(), rows.data(), q.data(), s.data(), W.data());
}

// ------------------------------------------------------------------------- regions
// spectral_igl.approx.region.grow_regions: for each group b of sources, the vertices within
// radii[b] of them along the edges of a symmetric CSR pattern, edge (i, j) of length
// sqrt(0.5 (h2[i] + h2[j])), found ring by ring (a vertex's distance through the ring before
// it, the smallest over its edges from that ring); a group whose region passes limits[b]
// vertices takes its source's whole component (labels) instead. Every distance is rounded as
// the numpy form rounds it, so both give the same regions. Returns the sorted keys
// b * n + vertex and the regions' offsets.
template <class I>
nb::tuple grow_regions(In1<I> indptr, In1<I> indices, In1<double> h2, In1<int64_t> sources, In1<int64_t> offsets,
                       In1<double> radii, In1<int64_t> limits, In1<int64_t> labels) {
    const int64_t n = int64_t(h2.shape(0)), groups = int64_t(offsets.shape(0)) - 1;
    if (groups < 0 || int64_t(radii.shape(0)) != groups || int64_t(limits.shape(0)) != groups)
        throw std::invalid_argument("radii and limits must have one entry per group");
    if (int64_t(indptr.shape(0)) != n + 1 || int64_t(labels.shape(0)) != n)
        throw std::invalid_argument("indptr must have n + 1 entries and labels n");
    const I *ip = indptr.data(), *ix = indices.data();
    const int64_t *off = offsets.data(), *src = sources.data(), *lab = labels.data();
    if (ip[0] != 0 || int64_t(ip[n]) > int64_t(indices.shape(0))) throw std::invalid_argument("indptr does not fit indices");
    for (int64_t i = 0; i < n; ++i)
        if (ip[i + 1] < ip[i]) throw std::invalid_argument("indptr must not decrease");
    for (int64_t p = 0; p < int64_t(ip[n]); ++p)
        if (ix[p] < 0 || int64_t(ix[p]) >= n) throw std::invalid_argument("indices out of range");
    if (off[0] != 0 || off[groups] != int64_t(sources.shape(0))) throw std::invalid_argument("offsets must run over the sources");
    for (int64_t b = 0; b < groups; ++b)
        if (off[b + 1] <= off[b]) throw std::invalid_argument("every group must hold a source");
    for (int64_t q = 0; q < int64_t(sources.shape(0)); ++q)
        if (src[q] < 0 || src[q] >= n) throw std::invalid_argument("sources out of range");
    std::vector<int64_t> keys, roff(size_t(groups) + 1, 0);
    {
        nb::gil_scoped_release rel;
        const double *hh = h2.data(), *rad = radii.data();
        const size_t nn = static_cast<size_t>(n);
        std::vector<int64_t> seen(nn, -1), ring(nn, -1);
        std::vector<double> dist(nn), cand(nn);
        std::vector<int64_t> region, front, next, found;
        int64_t stamp = 0;
        for (int64_t b = 0; b < groups; ++b) {
            region.assign(src + off[b], src + off[b + 1]);
            std::sort(region.begin(), region.end());
            region.erase(std::unique(region.begin(), region.end()), region.end());
            for (int64_t v : region) seen[v] = b, dist[v] = 0.0;
            front = region;
            bool over = int64_t(region.size()) > limits.data()[b];
            while (!front.empty() && !over) {
                ++stamp;
                found.clear();
                for (int64_t v : front)
                    for (I p = ip[v]; p < ip[v + 1]; ++p) {
                        const int64_t j = ix[p];
                        if (seen[j] == b) continue;
                        const double d = dist[v] + std::sqrt(0.5 * (hh[v] + hh[j]));
                        if (ring[j] != stamp) ring[j] = stamp, cand[j] = d, found.push_back(j);
                        else if (d < cand[j]) cand[j] = d;
                    }
                next.clear();
                for (int64_t j : found)
                    if (cand[j] <= rad[b]) seen[j] = b, dist[j] = cand[j], next.push_back(j), region.push_back(j);
                front.swap(next);
                over = int64_t(region.size()) > limits.data()[b];
            }
            if (over) {
                region.clear();
                const int64_t c = lab[src[off[b]]];
                for (int64_t v = 0; v < n; ++v)
                    if (lab[v] == c) region.push_back(v);
            }
            std::sort(region.begin(), region.end());
            for (int64_t v : region) keys.push_back(b * n + v);
            roff[size_t(b) + 1] = int64_t(keys.size());
        }
    }
    const size_t k = keys.size(), g = roff.size();
    return nb::make_tuple(to_numpy<int64_t>(std::move(keys), {k}), to_numpy<int64_t>(std::move(roff), {g}));
}

template <class T>
void bind_factor(nb::module_ &mod, const char *name) {
    using FT = Factor<T>;
    nb::class_<FT>(mod, name)
        .def("__init__",
             [](FT *self, std::shared_ptr<Symbolic> sym, In1<T> vals) {
                 if (i64(vals.shape(0)) != sym->nnz_in)
                     throw std::invalid_argument("values do not match the analysed pattern");
                 const T *v = vals.data();
                 nb::gil_scoped_release rel;
                 new (self) FT(sym, v);
             },
             nb::arg("symbolic"), nb::arg("values"))
        .def("solve",
             [](const FT &F, nb::ndarray<const T, nb::ndim<2>, nb::c_contig, nb::device::cpu> b) {
                 const Symbolic &s = *F.S;
                 const size_t n = s.n, k = b.shape(1);
                 if (b.shape(0) != n) throw std::invalid_argument("right-hand side has the wrong length");
                 std::vector<T> out(n * k);
                 const T *bd = b.data();
                 {
                     nb::gil_scoped_release rel;
                     std::vector<T> x(n * k);
                     for (size_t q = 0; q < n; ++q)
                         std::copy(bd + size_t(s.perm[q]) * k, bd + size_t(s.perm[q]) * k + k, x.begin() + q * k);
                     F.solve_internal(x.data(), k);
                     for (size_t q = 0; q < n; ++q)
                         std::copy(x.begin() + q * k, x.begin() + q * k + k, out.begin() + size_t(s.perm[q]) * k);
                 }
                 return to_numpy<T>(std::move(out), {n, k});
             },
             nb::arg("b"), "A^-1 b for b of shape (n, k), original ordering.")
        .def("inverse_columns",
             [](const FT &F, nb::ndarray<const int64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu> idx) {
                 const Symbolic &s = *F.S;
                 const size_t n = s.n, k = idx.shape(0);
                 const int64_t *ix = idx.data();
                 for (size_t c = 0; c < k; ++c)
                     if (ix[c] < 0 || ix[c] >= int64_t(n)) throw std::invalid_argument("column index out of range");
                 std::vector<T> out(n * k);
                 {
                     nb::gil_scoped_release rel;
                     std::vector<int> inv(n);
                     for (size_t q = 0; q < n; ++q) inv[s.perm[q]] = int(q);
                     std::vector<size_t> order(k);
                     for (size_t c = 0; c < k; ++c) order[c] = c;
                     std::stable_sort(order.begin(), order.end(),
                                      [&](size_t a, size_t b) { return inv[ix[a]] < inv[ix[b]]; });
                     std::vector<int> qs(k);
                     for (size_t j = 0; j < k; ++j) qs[j] = inv[ix[order[j]]];
                     std::vector<T> x = F.inverse_columns_internal(qs);
                     for (size_t q = 0; q < n; ++q) {
                         const T *xq = &x[q * k];
                         T *oq = &out[size_t(s.perm[q]) * k];
                         for (size_t j = 0; j < k; ++j) oq[order[j]] = xq[j];
                     }
                 }
                 return to_numpy<T>(std::move(out), {n, k});
             },
             nb::arg("idx"), "Columns idx of A^-1, shape (n, k), original ordering.")
        .def("inverse_diagonal",
             [](const FT &F) {
                 const Symbolic &s = *F.S;
                 std::vector<T> d;
                 {
                     nb::gil_scoped_release rel;
                     d = F.inverse_diagonal();
                 }
                 std::vector<T> out(s.n);
                 for (int q = 0; q < s.n; ++q) out[s.perm[q]] = d[q];
                 return to_numpy<T>(std::move(out), {size_t(s.n)});
             },
             "diag(A^-1) by selected inversion, original ordering.")
        .def("selected_inverse",
             [](const FT &F) {
                 const Symbolic &s = *F.S;
                 std::vector<T> vals(size_t(s.nnz_in), T(0));
                 {
                     nb::gil_scoped_release rel;
                     F.inverse_diagonal(vals.data());
                 }
                 return to_numpy<T>(std::move(vals), {size_t(s.nnz_in)});
             },
             "The entries of A^-1 on the analysed pattern (both triangles), in the order of the "
             "values given to the factorization, by selected inversion.")
        .def("pivots", [](const FT &F) {
            const Symbolic &s = *F.S;
            std::vector<T> out(s.n);
            for (int q = 0; q < s.n; ++q) out[s.perm[q]] = F.D[q];
            return to_numpy<T>(std::move(out), {size_t(s.n)});
        });
}

}  // namespace

NB_MODULE(_ldlt, mod) {
    mod.doc() = "Supernodal LDL^T of sparse symmetric matrices and the diagonal of their inverse.";
    nb::class_<Symbolic>(mod, "Symbolic")
        .def("__init__",
             [](Symbolic *self, In1<int32_t> indptr, In1<int32_t> indices, In1<int32_t> perm) {
                 const int n = int(perm.shape(0));
                 if (indptr.shape(0) != size_t(n) + 1) throw std::invalid_argument("indptr must have n + 1 entries");
                 const int *ip = indptr.data(), *ix = indices.data(), *p = perm.data();
                 const i64 nnz = i64(indices.shape(0));
                 nb::gil_scoped_release rel;
                 new (self) Symbolic(n, ip, ix, nnz, p);
             },
             nb::arg("indptr"), nb::arg("indices"), nb::arg("perm"),
             "Analyse the symmetric pattern (CSC, both triangles) under the ordering perm.")
        .def_ro("n", &Symbolic::n)
        .def_ro("nnz_L", &Symbolic::nnz_L)
        .def_ro("n_supernodes", &Symbolic::ns)
        .def_ro("flops", &Symbolic::flops)
        .def("largest_blas",
             [](const Symbolic &s, const std::string &op, int k) {
                 const blas::Largest c = s.largest_blas(op, k);
                 return nb::make_tuple(c.gemm, c.trxm);
             },
             nb::arg("op"), nb::arg("k") = 1,
             "(largest m*n*k of a gemm, largest min(m, n) of a trsm/trmm) that op ('factor', "
             "'solve' of k columns or 'inverse') passes to the BLAS; zeros when it calls none.")
        .def("permutation", [](const Symbolic &s) {
            std::vector<int32_t> p(s.perm.begin(), s.perm.end());
            return to_numpy<int32_t>(std::move(p), {size_t(s.n)});
        });
    mod.def("minimum_degree",
            [](In1<int32_t> indptr, In1<int32_t> indices) {
                const i64 n = i64(indptr.shape(0)) - 1;
                if (n < 0) throw std::invalid_argument("indptr must have n + 1 entries");
                const int32_t *ip = indptr.data(), *ix = indices.data();
                if (ip[n] > i64(indices.shape(0))) throw std::invalid_argument("indptr[n] exceeds indices");
                for (i64 k = 0; k < ip[n]; ++k)
                    if (ix[k] < 0 || ix[k] >= n) throw std::invalid_argument("indices out of range");
                std::vector<i64> p;
                {
                    nb::gil_scoped_release rel;
                    p = mindeg::order<int32_t>(n, ip, ix);
                }
                std::vector<int32_t> out(p.begin(), p.end());
                return to_numpy<int32_t>(std::move(out), {size_t(n)});
            },
            nb::arg("indptr"), nb::arg("indices"),
            "Minimum-degree ordering (perm[q] = original index) of the pattern of A + A^T "
            "(CSC; diagonal and duplicates ignored).");
    mod.def("set_blas",
            [](uintptr_t dgemm, uintptr_t zgemm, uintptr_t dtrsm, uintptr_t ztrsm, uintptr_t dtrmm, uintptr_t ztrmm) {
                blas::dgemm = reinterpret_cast<blas::gemm_t<double>>(dgemm);
                blas::zgemm = reinterpret_cast<blas::gemm_t<cplx>>(zgemm);
                blas::dtrsm = reinterpret_cast<blas::trxm_t<double>>(dtrsm);
                blas::ztrsm = reinterpret_cast<blas::trxm_t<cplx>>(ztrsm);
                blas::dtrmm = reinterpret_cast<blas::trxm_t<double>>(dtrmm);
                blas::ztrmm = reinterpret_cast<blas::trxm_t<cplx>>(ztrmm);
            },
            nb::arg("dgemm"), nb::arg("zgemm"), nb::arg("dtrsm"), nb::arg("ztrsm"), nb::arg("dtrmm"), nb::arg("ztrmm"),
            "Addresses of the Fortran-convention BLAS routines (scipy.linalg.cython_blas).");
    mod.def("set_blas_min_work", [](double w) { double old = blas::min_work; blas::min_work = w; return old; },
            nb::arg("work"), "Multiply-adds from which a dense block goes to BLAS (returns the previous value).");
    mod.def("blas_ready", &blas::ready);
    mod.def("kernel_isa", [] { return isa::avx2() ? "avx2" : "baseline"; },
            "Instruction set of the kernels in use: 'avx2', or 'baseline' (no AVX2 on this CPU, "
            "another compiler, or SPECTRAL_IGL_BASELINE=1).");
    mod.def("chebyshev_series", &chebyshev_series<int32_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("data"),
            nb::arg("offsets"), nb::arg("C"), nb::arg("rows"), nb::arg("t1").noconvert(), nb::arg("t0").noconvert(),
            nb::arg("W").noconvert(),
            "Terms 2..K of a Chebyshev recurrence on a block-diagonal CSR P: at term k, on the blocks in rows[:rows[k]], "
            "t_k = P t_{k-1} - t_{k-2} (written over t_{k-2}; the two swap roles each term) and "
            "W += C[block, k] t_k, rounded as the numpy form is (spectral_igl.approx.uniformization."
            "chebyshev_blocks); t1 and t0 are left as scratch.");
    mod.def("chebyshev_series", &chebyshev_series<int64_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("data"),
            nb::arg("offsets"), nb::arg("C"), nb::arg("rows"), nb::arg("t1").noconvert(), nb::arg("t0").noconvert(),
            nb::arg("W").noconvert());
    mod.def("poisson_series", &poisson_series<int32_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("data"),
            nb::arg("offsets"), nb::arg("lam"), nb::arg("rows"), nb::arg("q").noconvert(), nb::arg("s").noconvert(),
            nb::arg("W").noconvert(),
            "Terms 1..K of a Poisson series on a block-diagonal CSR P, from W's blocks: on the blocks in "
            "rows[:rows[k]], q_k = (P q_{k-1}) * (lam[block] / k) and W += q_k, rounded as the numpy form is "
            "(spectral_igl.approx.uniformization.uniformize_blocks); q and s are scratch.");
    mod.def("poisson_series", &poisson_series<int64_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("data"),
            nb::arg("offsets"), nb::arg("lam"), nb::arg("rows"), nb::arg("q").noconvert(), nb::arg("s").noconvert(),
            nb::arg("W").noconvert());
    mod.def("grow_regions", &grow_regions<int32_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("h2"),
            nb::arg("sources"), nb::arg("offsets"), nb::arg("radii"), nb::arg("limits"), nb::arg("labels"),
            "(keys, region offsets) of spectral_igl.approx.region.grow_regions, group by group.");
    mod.def("grow_regions", &grow_regions<int64_t>, nb::arg("indptr"), nb::arg("indices"), nb::arg("h2"),
            nb::arg("sources"), nb::arg("offsets"), nb::arg("radii"), nb::arg("limits"), nb::arg("labels"));
    bind_factor<double>(mod, "FactorD");
    bind_factor<cplx>(mod, "FactorZ");
}

// Minimum-degree fill-reducing ordering of a symmetric sparsity pattern, for the
// supernodal LDL^T in ldlt.cpp.
//
// Eliminating a vertex v of the graph of A connects all of v's remaining neighbours to
// each other; a minimum-degree ordering repeatedly eliminates a vertex with the fewest
// remaining neighbours, which keeps that fill small. Forming the cliques explicitly costs
// about as much as the factorization itself, so the elimination graph is kept implicitly,
// as a "quotient graph" (George & Liu, 1989):
//
//   * a variable is a vertex not yet eliminated; an element is an eliminated vertex,
//     standing for the clique that its elimination created, kept as the list L_e of the
//     variables in that clique;
//   * each variable i keeps E_i, the elements it belongs to, and A_i, its original
//     neighbours that are still variables and not already reached through an element.
//     Its neighbours in the elimination graph are A_i together with every L_e, e in E_i.
//
// Eliminating a pivot p makes it an element whose list L_p is A_p together with the lists
// of p's elements; those elements are then contained in L_p and are dropped ("absorbed").
// Every variable i of L_p replaces the absorbed elements by p in E_i and drops from A_i the
// variables of L_p (they are reached through p now). An element whose list lies entirely
// inside L_p is absorbed as well. Only the variables of L_p change their neighbourhoods.
//
// Two savings make this fast on meshes:
//
//   * Supervariables. Variables with the same E_i and A_i have the same neighbourhood from
//     now on and would be eliminated one right after the other with no further fill. They
//     are merged into one supervariable, weighted by the number of vertices it stands for,
//     and eliminated together (candidates are the variables of L_p with the same hash of
//     E_i and A_i; equal hashes are confirmed by comparing the sets).
//   * Degree bounds instead of exact degrees. The exact degree of i needs the union of the
//     lists of i's elements. Instead, for every element e met, |L_e \ L_p| is found by
//     subtracting the weights of its variables inside L_p from |L_e|, and the degree of i
//     (weighted, not counting i) is bounded by the smallest of
//       (vertices left) - |i|,   old degree + |L_p| - |i|,
//       |A_i| + |L_p| - |i| + sum over e in E_i, e != p, of |L_e \ L_p|,
//     the last being the approximate degree of Amestoy, Davis & Duff (1996). It is exact
//     when A_i and the sets L_e \ L_p (e != p) are pairwise disjoint.
//
// The pivot is taken from a bucket queue on these degrees (doubly linked lists, one per
// degree), so the ordering is deterministic. Vertices with more than max(16, 10 sqrt(n))
// neighbours (dense rows) would make every list long; they are left out of the graph and
// ordered last. The elimination tree's postorder and supernodes are found afterwards by
// the symbolic analysis in ldlt.cpp, which is why no postorder is computed here.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace mindeg {

enum : uint8_t { VARIABLE = 0, ELEMENT = 1, ABSORBED = 2, MERGED = 3, DENSE = 4 };

inline uint64_t mix(uint64_t x) {
    // a bijective 64-bit scramble, so that sums of scrambled ids rarely collide
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

// perm[k] = the original index of the vertex eliminated k-th. The pattern is given in
// compressed columns (indptr of n + 1 entries, row indices); it is symmetrized here and
// its diagonal and duplicate entries are ignored.
template <typename Idx>
std::vector<int64_t> order(int64_t n64, const Idx *indptr, const Idx *indices) {
    if (n64 < 0 || n64 >= int64_t(std::numeric_limits<int>::max()))
        throw std::invalid_argument("minimum_degree: n out of range");
    const int n = int(n64);
    std::vector<int64_t> perm;
    perm.reserve(size_t(n));
    if (n == 0) return perm;

    // ---- the graph of A + A^T without the diagonal, duplicates removed (A lists)
    std::vector<int64_t> start(size_t(n) + 1, 0);
    for (int j = 0; j < n; ++j)
        for (int64_t k = int64_t(indptr[j]); k < int64_t(indptr[j + 1]); ++k) {
            const int i = int(indices[k]);
            if (i != j) { ++start[size_t(i) + 1]; ++start[size_t(j) + 1]; }
        }
    for (int i = 0; i < n; ++i) start[size_t(i) + 1] += start[size_t(i)];
    std::vector<int> adj(static_cast<size_t>(start[size_t(n)]));
    {
        std::vector<int64_t> fill(start.begin(), start.end() - 1);
        for (int j = 0; j < n; ++j)
            for (int64_t k = int64_t(indptr[j]); k < int64_t(indptr[j + 1]); ++k) {
                const int i = int(indices[k]);
                if (i != j) { adj[size_t(fill[size_t(i)]++)] = j; adj[size_t(fill[size_t(j)]++)] = i; }
            }
    }
    std::vector<int> alen(size_t(n), 0);
    std::vector<int> mark(size_t(n), -1);
    for (int i = 0; i < n; ++i) {
        int len = 0;
        for (int64_t k = start[size_t(i)]; k < start[size_t(i) + 1]; ++k) {
            const int j = adj[size_t(k)];
            if (mark[size_t(j)] != i) { mark[size_t(j)] = i; adj[size_t(start[size_t(i)] + len++)] = j; }
        }
        alen[size_t(i)] = len;
    }
    std::fill(mark.begin(), mark.end(), -1);

    // ---- dense rows leave the graph and are ordered last
    std::vector<uint8_t> state(size_t(n), VARIABLE);
    const double dense = std::max(16.0, 10.0 * std::sqrt(double(n)));
    int ndense = 0;
    for (int i = 0; i < n; ++i)
        if (double(alen[size_t(i)]) > dense) { state[size_t(i)] = DENSE; ++ndense; }
    if (ndense > 0)
        for (int i = 0; i < n; ++i) {
            if (state[size_t(i)] == DENSE) { alen[size_t(i)] = 0; continue; }
            int len = 0;
            for (int k = 0; k < alen[size_t(i)]; ++k) {
                const int j = adj[size_t(start[size_t(i)] + k)];
                if (state[size_t(j)] != DENSE) adj[size_t(start[size_t(i)] + len++)] = j;
            }
            alen[size_t(i)] = len;
        }

    // ---- supervariables, element lists, degree buckets
    // A variable's elements E_i and variables A_i share its slot of adj: E_i first (ne[i]
    // entries), then A_i (alen[i]). The slot never overflows: a variable of L_p gains the
    // element p but loses p from A_i or an element of p's, absorbed into p.
    std::vector<int> nv(size_t(n), 1), deg(size_t(n), 0), ne(size_t(n), 0);
    std::vector<int> member_next(size_t(n), -1), member_last(static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) member_last[size_t(i)] = i;
    std::vector<int> pool;                                // lists L_e, back to back
    std::vector<int64_t> estart(size_t(n), 0);
    std::vector<int> elen(size_t(n), 0), esize(size_t(n), 0);

    std::vector<int> head(size_t(n) + 1, -1), next(size_t(n), -1), prev(size_t(n), -1);
    auto insert = [&](int i, int d) {
        deg[size_t(i)] = d;
        prev[size_t(i)] = -1;
        next[size_t(i)] = head[size_t(d)];
        if (head[size_t(d)] >= 0) prev[size_t(head[size_t(d)])] = i;
        head[size_t(d)] = i;
    };
    auto remove = [&](int i) {
        if (prev[size_t(i)] >= 0) next[size_t(prev[size_t(i)])] = next[size_t(i)];
        else head[size_t(deg[size_t(i)])] = next[size_t(i)];
        if (next[size_t(i)] >= 0) prev[size_t(next[size_t(i)])] = prev[size_t(i)];
    };
    int mindeg = n;
    for (int i = n - 1; i >= 0; --i)
        if (state[size_t(i)] == VARIABLE) {
            insert(i, alen[size_t(i)]);
            mindeg = std::min(mindeg, alen[size_t(i)]);
        }

    std::vector<int> wmark(size_t(n), -1), w(size_t(n), 0);  // |L_e \ L_p| of elements met
    std::vector<int> smark(size_t(n), -1);                  // set comparison of candidates
    uint64_t hmask = 1;
    while (hmask < uint64_t(n)) hmask <<= 1;
    std::vector<int> hhead(size_t(hmask), -1), hnext(size_t(n), -1);  // hash buckets
    --hmask;
    std::vector<uint64_t> hash(size_t(n), 0);
    std::vector<int64_t> bound(size_t(n), 0);
    std::vector<int> Lp;
    int64_t left = int64_t(n) - ndense;   // vertices not yet eliminated, dense ones aside
    int tag = 0, stag = 0;

    while (left > 0) {
        while (head[size_t(mindeg)] < 0) ++mindeg;
        const int p = head[size_t(mindeg)];
        remove(p);
        for (int m = p; m >= 0; m = member_next[size_t(m)]) perm.push_back(m);
        left -= nv[size_t(p)];

        // L_p: p's variables and those of its elements, which are absorbed into p
        ++tag;
        mark[size_t(p)] = tag;
        Lp.clear();
        int64_t lpw = 0;
        const int *slot = adj.data() + start[size_t(p)];
        for (int k = ne[size_t(p)]; k < ne[size_t(p)] + alen[size_t(p)]; ++k) {
            const int j = slot[k];
            if (state[size_t(j)] == VARIABLE && mark[size_t(j)] != tag) {
                mark[size_t(j)] = tag; Lp.push_back(j); lpw += nv[size_t(j)];
            }
        }
        for (int k = 0; k < ne[size_t(p)]; ++k) {
            const int e = slot[k];
            if (state[size_t(e)] != ELEMENT) continue;
            const int *Le = pool.data() + estart[size_t(e)];
            for (int q = 0; q < elen[size_t(e)]; ++q) {
                const int j = Le[q];
                if (state[size_t(j)] == VARIABLE && mark[size_t(j)] != tag) {
                    mark[size_t(j)] = tag; Lp.push_back(j); lpw += nv[size_t(j)];
                }
            }
            state[size_t(e)] = ABSORBED;
        }
        state[size_t(p)] = ELEMENT;
        ne[size_t(p)] = alen[size_t(p)] = 0;

        // pass 1: each variable of L_p drops absorbed elements and the variables reached
        // through p; the elements it keeps get |L_e \ L_p|
        for (int i : Lp) {
            remove(i);
            int *si = adj.data() + start[size_t(i)];
            const int nei = ne[size_t(i)], nai = alen[size_t(i)];
            int ke = 0;
            for (int k = 0; k < nei; ++k) {
                const int e = si[k];
                if (state[size_t(e)] != ELEMENT) continue;
                si[ke++] = e;
                if (wmark[size_t(e)] != tag) { wmark[size_t(e)] = tag; w[size_t(e)] = esize[size_t(e)]; }
                w[size_t(e)] -= nv[size_t(i)];
            }
            int ka = 0;
            for (int k = nei; k < nei + nai; ++k) {
                const int j = si[k];
                if (state[size_t(j)] == VARIABLE && mark[size_t(j)] != tag) si[ke + ka++] = j;
            }
            ne[size_t(i)] = ke;
            alen[size_t(i)] = ka;
        }

        // pass 2: elements inside L_p are absorbed, p joins E_i; degree bound without L_p
        // and a hash of (E_i, A_i) into buckets (about 2|L_p| of them: a small table
        // stays in cache)
        uint64_t pmask = 1;
        while (pmask < 2 * uint64_t(Lp.size()) && pmask <= hmask) pmask <<= 1;
        pmask = std::min(pmask - 1, hmask);
        for (int i : Lp) {
            int *si = adj.data() + start[size_t(i)];
            const int nei = ne[size_t(i)], nai = alen[size_t(i)];
            int ke = 0;
            int64_t ext = 0;
            uint64_t h = mix(uint64_t(p));
            for (int k = 0; k < nei; ++k) {
                const int e = si[k];
                if (state[size_t(e)] != ELEMENT) continue;
                if (w[size_t(e)] <= 0) { state[size_t(e)] = ABSORBED; continue; }
                si[ke++] = e;
                ext += w[size_t(e)];
                h += mix(uint64_t(e));
            }
            // A_i moves to just after E_i and p (overlapping: memmove)
            if (start[size_t(i)] + ke + 1 + nai > start[size_t(i) + 1])
                throw std::logic_error("minimum_degree: a variable's lists outgrew its slot");
            if (nai > 0 && ke + 1 != nei) std::memmove(si + ke + 1, si + nei, sizeof(int) * size_t(nai));
            si[ke] = p;
            ne[size_t(i)] = ke + 1;
            for (int k = ke + 1; k < ke + 1 + nai; ++k) {
                const int j = si[k];
                ext += nv[size_t(j)];
                h += mix(uint64_t(j) + uint64_t(n));
            }
            bound[size_t(i)] = ext;
            hash[size_t(i)] = h;
            const size_t b = size_t(h & pmask);
            hnext[size_t(i)] = hhead[b];
            hhead[b] = i;
        }

        // supervariables: variables of L_p with equal E_i and A_i are merged
        for (int i0 : Lp) {
            const size_t b = size_t(hash[size_t(i0)] & pmask);
            int first = hhead[b];
            if (first < 0) continue;
            hhead[b] = -1;
            for (int i = first; i >= 0; i = hnext[size_t(i)]) {
                if (state[size_t(i)] != VARIABLE || hnext[size_t(i)] < 0) continue;
                bool marked = false;
                const int *si = adj.data() + start[size_t(i)];
                const int li = ne[size_t(i)] + alen[size_t(i)];
                for (int j = hnext[size_t(i)]; j >= 0; j = hnext[size_t(j)]) {
                    if (state[size_t(j)] != VARIABLE || hash[size_t(j)] != hash[size_t(i)]
                        || ne[size_t(j)] != ne[size_t(i)] || alen[size_t(j)] != alen[size_t(i)])
                        continue;
                    if (!marked) {
                        ++stag;
                        for (int k = 0; k < li; ++k) smark[size_t(si[k])] = stag;
                        marked = true;
                    }
                    const int *sj = adj.data() + start[size_t(j)];
                    bool same = true;
                    for (int k = 0; same && k < li; ++k) same = smark[size_t(sj[k])] == stag;
                    if (!same) continue;
                    nv[size_t(i)] += nv[size_t(j)];
                    nv[size_t(j)] = 0;
                    state[size_t(j)] = MERGED;
                    member_next[size_t(member_last[size_t(i)])] = j;
                    member_last[size_t(i)] = member_last[size_t(j)];
                    ne[size_t(j)] = alen[size_t(j)] = 0;
                }
            }
        }

        // new degrees; p's list keeps the surviving supervariables
        estart[size_t(p)] = int64_t(pool.size());
        for (int i : Lp) {
            if (state[size_t(i)] != VARIABLE) continue;
            pool.push_back(i);
            const int64_t self = nv[size_t(i)];
            int64_t d = std::min(left - self, int64_t(deg[size_t(i)]) + lpw - self);
            d = std::min(d, bound[size_t(i)] + lpw - self);
            d = std::max<int64_t>(d, 0);
            insert(i, int(d));
            mindeg = std::min(mindeg, int(d));
        }
        elen[size_t(p)] = int(int64_t(pool.size()) - estart[size_t(p)]);
        esize[size_t(p)] = int(lpw);
    }
    for (int i = 0; i < n; ++i)
        if (state[size_t(i)] == DENSE) perm.push_back(i);
    return perm;
}

}  // namespace mindeg

/**
 * pfvi_solve.c: the stage solve. A step's stage equations (pfvi_stages.c,
 * either form) are R(y) = y - G(y) = 0 in the unknowns y (m = s - 1 rows of
 * 3 components per particle), where a round y -> G(y) evaluates the forces
 * at the stage points x(y) and solves the equations' linear part for them:
 *     G(y) = yc - S F(x(y)),   x_k(y) = base_k + sum_l X[k][l] y_l,
 * S (m x s) the forces' weights and X (s x m) the stages' dependence on the
 * unknowns (struct pfvi_solve_form, one per distinct fit), F_k the force the
 * round carries at stage k (fscale a_k, plus u2 d_k for the fitting "exact").
 *
 * Rather than iterating G (a fixed point whose contraction is about the
 * step's kappa, 7-9 rounds at the defaults), each round is corrected by
 * Newton's method with each body's dominant coupling only: the tidal tensor
 * of its partner, dA/dx = alpha (3 n n^T - I), alpha = mu/r^3, evaluated at
 * every stage of the first iterate (one factorisation per step). Mutual
 * partners (a binary, a star and its closest planet) are corrected in their
 * relative coordinate with mu = G (m_i + m_j), their barycentre by the plain
 * round; every other body after its centre (its partner, or the barycentre
 * of a pair bound more tightly than it is to that partner), with the
 * centre's correction on its right-hand side. The per-body matrix
 *     M = I + S diag(g) X (x) I_3 + sum_k d_k (S e_k (x) n_k)(X^T e_k (x) n_k)^T
 * (g_k = u2 - fscale alpha_k, d_k = 3 fscale alpha_k) is an isotropic part
 * Kronecker with I_3 plus one rank-one term per stage, solved by Woodbury's
 * identity: two factorisations of at most 7 x 7 per step and body (the
 * unknowns the forces depend on; K the stages whose force acts within the
 * step), a few hundred flops per round.
 *
 * The first iterate (pfvi_solve_predict) draws each body along its two-body
 * orbit about that centre (universal variables), the rest of its
 * acceleration extrapolated from the last step's stages and integrated by
 * the classical form's own stage formula (none for two bodies alone, whose
 * rest is round-off).
 *
 * The residual G(y) - y of each round is the exact one: the partner model
 * changes only how fast the iterates converge, never what they converge to.
 *
 * The rounds stop by the measured rate (pfvi_solve_verdict): with theta the
 * ratio of the last two corrections, once theta/(1 - theta) times the last
 * correction is below the doubles' resolution, the corrected iterate is
 * taken through one final round, which must confirm it; a change that grows
 * refreshes the Jacobians at the current iterate, and growing again, drops
 * them for the plain round (counted in n_solve_recovered); a third time the
 * solve has failed (the control halves the step: n_solve_halved).
 * docs/solve.md.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "pfvi.h"

/* ---------------------------------------------------------- small LU */

#define LU_MAX PFVI_STAGES_MAX

// LU factorisation with partial pivoting of the n x n matrix A (n <= 8) in
// place, the pivots' reciprocals, and the rows' order: row k of the factors
// is row perm[k] of A (the swaps composed, so a solve gathers its right-hand
// side in one pass of independent loads, not a chain of swaps through
// memory); 0 if a pivot is zero or not finite.
// A row of A (LU_MAX = 8 doubles) is two vectors of lanes: a row swap is
// the whole row's (the columns beyond n are never read), and the
// elimination A[i][j] -= g A[k][j] is made in every lane, the result kept
// only in the lanes j > k (the others, L's entries and A[i][k], as they
// were): each kept lane is the scalar loop's operation, the same bits.
typedef char lu_rows_are_two_vectors[(LU_MAX == 8) ? 1 : -1];


static inline __attribute__((always_inline)) int lu_factor(int n, double (*A)[LU_MAX], int* perm, double* inverse){
    const pfvi_lane_mask column_lo = {0, 1, 2, 3}, column_hi = {4, 5, 6, 7};
    for (int k=0; k<n; k++){
        perm[k] = k;
    }
    for (int k=0; k<n; k++){
        // (the pivot's magnitude carried beside its row: the same
        // comparisons as fabs(A[i][k]) > fabs(A[p][k]))
        int p = k;
        double largest = fabs(A[k][k]);
        for (int i=k+1; i<n; i++){
            const double a = fabs(A[i][k]);
            p = (a > largest) ? i : p;
            largest = (a > largest) ? a : largest;
        }
        const int t = perm[p]; perm[p] = perm[k]; perm[k] = t;
        pfvi_lanes rk_lo, rk_hi;
        memcpy(&rk_lo, &A[p][0], sizeof(rk_lo));
        memcpy(&rk_hi, &A[p][4], sizeof(rk_hi));
        if (p != k){
            memcpy(&A[p][0], &A[k][0], sizeof(A[p]));
            memcpy(&A[k][0], &rk_lo, sizeof(rk_lo));
            memcpy(&A[k][4], &rk_hi, sizeof(rk_hi));
        }
        if (!(A[k][k] != 0.) || !isfinite(A[k][k])){
            return 0;
        }
        inverse[k] = 1./A[k][k];
        const pfvi_lane_mask kk = {k, k, k, k};
        const pfvi_lane_mask right_lo = column_lo > kk, right_hi = column_hi > kk;
        for (int i=k+1; i<n; i++){
            const double g = A[i][k]*inverse[k];
            const pfvi_lanes G = {g, g, g, g};
            pfvi_lanes lo, hi;
            memcpy(&lo, &A[i][0], sizeof(lo));
            memcpy(&hi, &A[i][4], sizeof(hi));
            lo = lanes_where(right_lo, lo - G*rk_lo, lo);
            hi = lanes_where(right_hi, hi - G*rk_hi, hi);
            memcpy(&A[i][0], &lo, sizeof(lo));
            memcpy(&A[i][4], &hi, sizeof(hi));
            A[i][k] = g;
        }
    }
    return 1;
}

// Solves with lu_factor's factors for `width` right-hand sides b[row][0 ..
// width-1] in place. (The factors are of the rows as finally permuted:
// the rows gathered first, then L, then U.)
static inline __attribute__((always_inline)) void lu_solve(int n, const double (*A)[LU_MAX], const int* perm,
        const double* inverse, double (*b)[3], int width){
    double gathered[LU_MAX][3];
    for (int k=0; k<n; k++){
        for (int c=0; c<width; c++){
            gathered[k][c] = b[perm[k]][c];
        }
    }
    for (int k=0; k<n; k++){
        for (int c=0; c<width; c++){
            b[k][c] = gathered[k][c];
        }
    }
    for (int k=0; k<n; k++){
        for (int i=k+1; i<n; i++){
            const double g = A[i][k];
            for (int c=0; c<width; c++){
                b[i][c] -= g*b[k][c];
            }
        }
    }
    for (int k=n-1; k>=0; k--){
        for (int c=0; c<width; c++){
            double sum = b[k][c];
            for (int j=k+1; j<n; j++){
                sum -= A[k][j]*b[j][c];
            }
            b[k][c] = sum*inverse[k];
        }
    }
}

/* ------------------------------------------- Newton with the partner's pull */

// The unknowns the forces within the step depend on (the leading ones: the
// classical form's end position is not among them).
static int coupled_unknowns(const struct pfvi_solve_form* f){
    int mc = 0;
    for (int j=0; j<f->m; j++){
        for (int k=1; k<=f->k_last; k++){
            mc = (f->X[k][j] != 0.) ? j + 1 : mc;
        }
    }
    return mc;
}

// The classical form's Q = P^-1 S (columns 1 .. K) and Woodbury's
// capacitance matrix, with the K columns as vector lanes (lane c: column
// 1 + c): each lane the scalar solve's and product's operations, so the
// bits of lu_solve's columns and the scalar loop's entries.
static inline __attribute__((always_inline)) void newton_factor_classical_rest(const struct pfvi_solve_form* f,
        const double (*n)[3], struct pfvi_newton* u, const int mc, const int K){
#define ALL(x) ((pfvi_lanes){(x), (x), (x), (x)})
    pfvi_lanes lo[PFVI_STAGES_MAX], hi[PFVI_STAGES_MAX];
    for (int k=0; k<mc; k++){
        // (S's rows in the factors' order)
        double row[8] = {0., 0., 0., 0., 0., 0., 0., 0.};
        for (int c=0; c<K; c++){
            row[c] = f->S[u->Pperm[k]][1 + c];
        }
        memcpy(&lo[k], row, sizeof(lo[k]));
        memcpy(&hi[k], row + 4, sizeof(hi[k]));
    }
    for (int k=0; k<mc; k++){
        for (int i=k+1; i<mc; i++){
            const pfvi_lanes g = ALL(u->P[i][k]);
            lo[i] -= g*lo[k];
            hi[i] -= g*hi[k];
        }
    }
    for (int k=mc-1; k>=0; k--){
        pfvi_lanes sl = lo[k], sh = hi[k];
        for (int j=k+1; j<mc; j++){
            const pfvi_lanes a = ALL(u->P[k][j]);
            sl -= a*lo[j];
            sh -= a*hi[j];
        }
        lo[k] = sl*ALL(u->Pinv[k]);
        hi[k] = sh*ALL(u->Pinv[k]);
    }
    double d[8] = {0.}, nx[8] = {0.}, ny[8] = {0.}, nz[8] = {0.};
    for (int l=0; l<mc; l++){
        double row[8];
        memcpy(row, &lo[l], sizeof(lo[l]));
        memcpy(row + 4, &hi[l], sizeof(hi[l]));
        for (int c=0; c<K; c++){
            u->Q[l][1 + c] = row[c];
        }
    }
    for (int c=0; c<K; c++){
        d[c] = u->d[1 + c];
        nx[c] = n[1 + c][0]; ny[c] = n[1 + c][1]; nz[c] = n[1 + c][2];
    }
    pfvi_lanes D[2], NX[2], NY[2], NZ[2];
    for (int h=0; h<2; h++){
        memcpy(&D[h], d + 4*h, sizeof(D[h]));
        memcpy(&NX[h], nx + 4*h, sizeof(NX[h]));
        memcpy(&NY[h], ny + 4*h, sizeof(NY[h]));
        memcpy(&NZ[h], nz + 4*h, sizeof(NZ[h]));
    }
    for (int k=1; k<=K; k++){
        // H[k][kk] = Q[k-1][kk] (the shift); C = delta + d_kk H (n_k . n_kk)
        double hrow[8] = {0., 0., 0., 0., 0., 0., 0., 0.};
        for (int c=0; c<K; c++){
            hrow[c] = u->Q[k-1][1 + c];
        }
        // (whole rows of C: the lanes c >= K are never read)
        double identity[8] = {0., 0., 0., 0., 0., 0., 0., 0.};
        identity[k-1] = 1.;
        for (int h=0; h<2; h++){
            pfvi_lanes H, I;
            memcpy(&H, hrow + 4*h, sizeof(H));
            memcpy(&I, identity + 4*h, sizeof(I));
            const pfvi_lanes nn = ALL(n[k][0])*NX[h] + ALL(n[k][1])*NY[h] + ALL(n[k][2])*NZ[h];
            const pfvi_lanes v = I + (D[h]*H)*nn;
            memcpy(&u->C[k-1][4*h], &v, sizeof(v));
        }
    }
#undef ALL
}

// One body's (or one mutual pair's relative) Newton matrix at the stages of
// the first iterate over the coupled unknowns' components,
//     M = P (x) I_3 + sum_k d_k (S e_k (x) n_k)(X^T e_k (x) n_k)^T,
// P = I + S diag(g) X: an isotropic part, Kronecker with I_3, and one
// rank-one term per stage, factorised for Woodbury's identity: P (mc x mc)
// and the capacitance C = I + [d_k' (X P^-1 S)[k][k'] (n_k . n_k')] (K x K).
// (P alone is the stage matrix of an oscillator of frequency alpha^1/2, with
// Lobatto IIIA-IIIB's eigenvalues it is regular for every real step.)
// (cs: 0, or the classical form's s as a constant, for loops the compiler unrolls)
static inline __attribute__((always_inline)) int newton_factor_form(const struct pfvi_solve_form* f,
        const double (*n)[3], const double* alpha, struct pfvi_newton* u, const int cs){
    const int classical = (cs > 0);
    const int K = classical ? cs - 2 : f->k_last, mc = classical ? cs - 2 : coupled_unknowns(f);
    u->mc = mc;
    double g[PFVI_STAGES_MAX];
    for (int k=1; k<=K; k++){
        u->d[k] = 3.*f->fscale*alpha[k];
        u->gc[k] = -f->fscale*alpha[k];
        g[k] = f->u2 + u->gc[k];
        u->n[k][0] = n[k][0]; u->n[k][1] = n[k][1]; u->n[k][2] = n[k][2];
    }
    for (int l=0; l<mc; l++){
        for (int j=0; j<mc; j++){
            double sum = (l == j) ? 1. : 0.;
            if (classical){
                sum += f->S[l][j+1]*g[j+1];   // (X the shift: X[k][j] = 1 at k = j + 1)
            }else{
                for (int k=1; k<=K; k++){
                    sum += f->S[l][k]*g[k]*f->X[k][j];
                }
            }
            u->P[l][j] = sum;
        }
    }
    if (!lu_factor(mc, u->P, u->Pperm, u->Pinv)){
        return 0;
    }
    if (classical){
        newton_factor_classical_rest(f, n, u, mc, K);
        return lu_factor(K, u->C, u->Cperm, u->Cinv);
    }
    // Q = P^-1 S, its columns 1 .. K (in rows of up to 3: the solve's width).
    for (int k0=1; k0<=K; k0+=3){
        double cols[PFVI_STAGES_MAX][3];
        const int width = (K - k0 + 1 < 3) ? K - k0 + 1 : 3;
        for (int l=0; l<mc; l++){
            for (int c=0; c<width; c++){
                cols[l][c] = f->S[l][k0 + c];
            }
        }
        lu_solve(mc, (const double (*)[LU_MAX])u->P, u->Pperm, u->Pinv, cols, width);
        for (int l=0; l<mc; l++){
            for (int c=0; c<width; c++){
                u->Q[l][k0 + c] = cols[l][c];
            }
        }
    }
    for (int k=1; k<=K; k++){
        for (int kk=1; kk<=K; kk++){
            double H = 0.;
            if (classical){
                H = u->Q[k-1][kk];
            }else{
                for (int l=0; l<mc; l++){
                    H += f->X[k][l]*u->Q[l][kk];
                }
            }
            const double nn = n[k][0]*n[kk][0] + n[k][1]*n[kk][1] + n[k][2]*n[kk][2];
            u->C[k-1][kk-1] = ((k == kk) ? 1. : 0.) + u->d[kk]*H*nn;
        }
    }
    return lu_factor(K, u->C, u->Cperm, u->Cinv);
}

PFVI_VECTOR_CLONES
static int newton_factor(const struct pfvi_solve_form* f, const double (*n)[3], const double* alpha,
        struct pfvi_newton* u){
    if (f->classical && f->k_last == f->m - 1){
        switch (f->m + 1){
            case 3: return newton_factor_form(f, n, alpha, u, 3);
            case 4: return newton_factor_form(f, n, alpha, u, 4);
            case 5: return newton_factor_form(f, n, alpha, u, 5);
            case 6: return newton_factor_form(f, n, alpha, u, 6);
            case 7: return newton_factor_form(f, n, alpha, u, 7);
            case 8: return newton_factor_form(f, n, alpha, u, 8);
            default: break;
        }
    }
    return newton_factor_form(f, n, alpha, u, 0);
}

// The partner's tidal tensor at stage k applied to dx: J dx = g dx + d n (n . dx).
static void tidal_apply(const struct pfvi_newton* u, int k, double g, const double dx[3], double out[3]){
    const double nd = u->d[k]*(u->n[k][0]*dx[0] + u->n[k][1]*dx[1] + u->n[k][2]*dx[2]);
    for (int c=0; c<3; c++){
        out[c] = g*dx[c] + nd*u->n[k][c];
    }
}

// newton_apply for the classical form of s stages, written for a constant s
// (each s its own unrolled loops): X is the shift Q^k = q_k + y[k-1], the
// coupled unknowns are the s - 2 interior stages, and the end y[s-2]
// follows from them. Each row's three components are the lanes of one
// vector (the fourth zero): every lane is the scalar operation on that
// component, so the bits are those of the loop over components.
static inline __attribute__((always_inline)) void newton_apply_classical_n(const struct pfvi_solve_form* f,
        const struct pfvi_newton* u, double (*b)[3], const int s){
    const int mc = s - 2;
#define ROW(x, y, z) ((pfvi_lanes){(x), (y), (z), 0.})
#define ALL(x) ((pfvi_lanes){(x), (x), (x), (x)})
    // (the coupled rows gathered in the factors' order: with s a constant,
    // every index below is one, and B and t can stay in registers)
    pfvi_lanes B[PFVI_STAGES_MAX];
    for (int k=0; k<mc; k++){
        const int p = u->Pperm[k];
        B[k] = ROW(b[p][0], b[p][1], b[p][2]);
    }
    B[s-2] = ROW(b[s-2][0], b[s-2][1], b[s-2][2]);
    for (int k=0; k<mc; k++){
        for (int i=k+1; i<mc; i++){
            B[i] -= ALL(u->P[i][k])*B[k];
        }
    }
    for (int k=mc-1; k>=0; k--){
        pfvi_lanes sum = B[k];
        for (int j=k+1; j<mc; j++){
            sum -= ALL(u->P[k][j])*B[j];
        }
        B[k] = sum*ALL(u->Pinv[k]);
    }
    pfvi_lanes n[PFVI_STAGES_MAX];
    double nB[PFVI_STAGES_MAX], t[PFVI_STAGES_MAX];
    for (int k=1; k<=mc; k++){
        n[k] = ROW(u->n[k][0], u->n[k][1], u->n[k][2]);
        nB[k-1] = u->n[k][0]*B[k-1][0] + u->n[k][1]*B[k-1][1] + u->n[k][2]*B[k-1][2];
    }
    for (int k=0; k<mc; k++){
        t[k] = nB[u->Cperm[k]];
    }
    for (int k=0; k<mc; k++){
        for (int i=k+1; i<mc; i++){
            t[i] -= u->C[i][k]*t[k];
        }
    }
    for (int k=mc-1; k>=0; k--){
        double sum = t[k];
        for (int j=k+1; j<mc; j++){
            sum -= u->C[k][j]*t[j];
        }
        t[k] = sum*u->Cinv[k];
    }
    for (int k=1; k<=mc; k++){
        const double tau = t[k-1]*u->d[k];
        for (int l=0; l<mc; l++){
            const double q = tau*u->Q[l][k];
            B[l] -= ALL(q)*n[k];
        }
    }
    for (int k=1; k<=mc; k++){
        // tidal_apply: J dx = g dx + d n (n . dx)
        const pfvi_lanes dx = B[k-1];
        const double nd = u->d[k]*(u->n[k][0]*dx[0] + u->n[k][1]*dx[1] + u->n[k][2]*dx[2]);
        const pfvi_lanes Jdx = ALL(u->gc[k])*dx + ALL(nd)*n[k];
        B[s-2] -= ALL(f->S[s-2][k])*Jdx;
    }
    for (int l=0; l<s-1; l++){
        b[l][0] = B[l][0]; b[l][1] = B[l][1]; b[l][2] = B[l][2];
    }
#undef ROW
#undef ALL
}

// b <- M^-1 b for a factorised unit (b: m rows of 3): the coupled unknowns
// by Woodbury's identity, the others (the classical end) from them.
PFVI_VECTOR_CLONES
static void newton_apply(const struct pfvi_solve_form* f, const struct pfvi_newton* u, double (*b)[3]){
    if (f->classical){
        switch (f->m + 1){
            case 3: newton_apply_classical_n(f, u, b, 3); return;
            case 4: newton_apply_classical_n(f, u, b, 4); return;
            case 5: newton_apply_classical_n(f, u, b, 5); return;
            case 6: newton_apply_classical_n(f, u, b, 6); return;
            case 7: newton_apply_classical_n(f, u, b, 7); return;
            default: newton_apply_classical_n(f, u, b, PFVI_STAGES_MAX); return;
        }
    }
    const int mc = u->mc, K = f->k_last;
    lu_solve(mc, (const double (*)[LU_MAX])u->P, u->Pperm, u->Pinv, b, 3);
    double t[PFVI_STAGES_MAX][3];
    for (int k=1; k<=K; k++){
        double xi[3] = {0., 0., 0.};
        for (int l=0; l<mc; l++){
            const double X = f->X[k][l];
            xi[0] += X*b[l][0]; xi[1] += X*b[l][1]; xi[2] += X*b[l][2];
        }
        t[k-1][0] = u->n[k][0]*xi[0] + u->n[k][1]*xi[1] + u->n[k][2]*xi[2];
    }
    lu_solve(K, (const double (*)[LU_MAX])u->C, u->Cperm, u->Cinv, t, 1);
    for (int k=1; k<=K; k++){
        const double tau = t[k-1][0]*u->d[k];
        for (int l=0; l<mc; l++){
            const double q = tau*u->Q[l][k];
            b[l][0] -= q*u->n[k][0]; b[l][1] -= q*u->n[k][1]; b[l][2] -= q*u->n[k][2];
        }
    }
    for (int k=1; mc < f->m && k<=K; k++){
        double dx[3] = {0., 0., 0.}, Jdx[3];
        for (int j=0; j<mc; j++){
            const double X = f->X[k][j];
            dx[0] += X*b[j][0]; dx[1] += X*b[j][1]; dx[2] += X*b[j][2];
        }
        tidal_apply(u, k, f->u2 + u->gc[k], dx, Jdx);
        for (int l=mc; l<f->m; l++){
            const double S = f->S[l][k];
            b[l][0] -= S*Jdx[0]; b[l][1] -= S*Jdx[1]; b[l][2] -= S*Jdx[2];
        }
    }
}

// Adds to b the partner's correction as it acts on this body:
// S [fscale J_k dx_p,k]_k, dx_p the partner's stage displacements. Each row
// of b (and of dx) is one vector of lanes (x, y, z, 0), every lane the
// scalar expression for its component: the bits of the loop over
// components. (m, K: f's rows and forced stages; constants where the
// compiler should unroll, as in newton_apply_classical_n.)
static inline __attribute__((always_inline)) void newton_cross_n(const struct pfvi_solve_form* f,
        const struct pfvi_newton* u, const struct pfvi_solve_form* fp, const double (*Dp)[3], double (*b)[3],
        const int m, const int K){
#define ROW(x, y, z) ((pfvi_lanes){(x), (y), (z), (z)})   // (the fourth lane is never stored)
#define ALL(x) ((pfvi_lanes){(x), (x), (x), (x)})
    pfvi_lanes B[PFVI_STAGES_MAX];
    for (int l=0; l<m; l++){
        B[l] = ROW(b[l][0], b[l][1], b[l][2]);
    }
    for (int k=1; k<=K; k++){
        pfvi_lanes dx = {0., 0., 0., 0.};
        if (fp->classical){
            dx = ROW(Dp[k-1][0], Dp[k-1][1], Dp[k-1][2]);
        }else{
            for (int l=0; l<fp->m; l++){
                dx += ALL(fp->X[k][l])*ROW(Dp[l][0], Dp[l][1], Dp[l][2]);
            }
        }
        // tidal_apply: J dx = g dx + d n (n . dx)
        const double nd = u->d[k]*(u->n[k][0]*dx[0] + u->n[k][1]*dx[1] + u->n[k][2]*dx[2]);
        const pfvi_lanes J = ALL(u->gc[k])*dx + ALL(nd)*ROW(u->n[k][0], u->n[k][1], u->n[k][2]);
        for (int l=0; l<m; l++){
            B[l] += ALL(f->S[l][k])*J;
        }
    }
    for (int l=0; l<m; l++){
        b[l][0] = B[l][0]; b[l][1] = B[l][1]; b[l][2] = B[l][2];
    }
#undef ROW
#undef ALL
}

PFVI_VECTOR_CLONES
static void newton_cross(const struct pfvi_solve_form* f, const struct pfvi_newton* u,
        const struct pfvi_solve_form* fp, const double (*Dp)[3], double (*b)[3]){
    if (f->classical && f->k_last == f->m - 1){
        switch (f->m + 1){
            case 3: newton_cross_n(f, u, fp, Dp, b, 2, 1); return;
            case 4: newton_cross_n(f, u, fp, Dp, b, 3, 2); return;
            case 5: newton_cross_n(f, u, fp, Dp, b, 4, 3); return;
            case 6: newton_cross_n(f, u, fp, Dp, b, 5, 4); return;
            case 7: newton_cross_n(f, u, fp, Dp, b, 6, 5); return;
            case 8: newton_cross_n(f, u, fp, Dp, b, 7, 6); return;
            default: break;
        }
    }
    newton_cross_n(f, u, fp, Dp, b, f->m, f->k_last);
}

// What body i is corrected and predicted about: its partner p, or, where
// p is one of a pair of mutual partners that i is not in and that is bound
// more tightly than i is to p (a body about a binary, a planet about a star
// and a closer planet), that pair's barycentre. Positions of the centre: (1 - w) (x_p + g) + w (x_q + g + g_pq)
// with g the ghost image of i's partner and g_pq that of the pair's.
struct centre_ref {
    size_t p, q;        // q: SIZE_MAX for p alone
    double w;           // m_q/(m_p + m_q)
    double mass;        // m_p (+ m_q)
    double g[3], gv[3]; // the partner's image
    double gq[3], gqv[3];
};

static inline __attribute__((always_inline)) struct centre_ref centre_of(const struct pfvi_state* st,
        const struct pfvi_field* field, size_t i){
    struct centre_ref c = {.w = 0.};
    c.p = st->newton[i].partner;
    c.q = st->newton[i].companion;
    const struct reb_vec6d* const g = &field->images[st->partners[i].image];
    c.g[0] = g->x; c.g[1] = g->y; c.g[2] = g->z;
    c.gv[0] = g->vx; c.gv[1] = g->vy; c.gv[2] = g->vz;
    const double mp = st->start[c.p].m;
    c.mass = mp;
    if (c.q != SIZE_MAX){
        const double mq = st->start[c.q].m;
        const struct reb_vec6d* const gq = &field->images[st->partners[c.p].image];
        c.gq[0] = gq->x; c.gq[1] = gq->y; c.gq[2] = gq->z;
        c.gqv[0] = gq->vx; c.gqv[1] = gq->vy; c.gqv[2] = gq->vz;
        c.mass = mp + mq;
        c.w = mq/c.mass;
    }
    return c;
}

// The centre's point from per-body points X[body][k] (solve_x or the last step's stages).
static void centre_point(const struct centre_ref* c, const double (*X)[PFVI_STAGES_MAX][3], int k, double out[3]){
    for (int d=0; d<3; d++){
        const double xp = X[c->p][k][d] + c->g[d];
        out[d] = (c->q == SIZE_MAX) ? xp : (1. - c->w)*xp + c->w*(X[c->q][k][d] + c->g[d] + c->gq[d]);
    }
}

// The centre at the step's start: position, velocity, acceleration.
static void centre_start(const struct centre_ref* c, const struct pfvi_state* st, double x[3], double v[3], double a[3]){
    const struct reb_particle* const pp = &st->start[c->p];
    const double px[3] = {pp->x, pp->y, pp->z}, pv[3] = {pp->vx, pp->vy, pp->vz};
    for (int d=0; d<3; d++){
        x[d] = px[d] + c->g[d];
        v[d] = pv[d] + c->gv[d];
        a[d] = st->end[c->p].a[d];
    }
    if (c->q != SIZE_MAX){
        const struct reb_particle* const pq = &st->start[c->q];
        const double qx[3] = {pq->x, pq->y, pq->z}, qv[3] = {pq->vx, pq->vy, pq->vz};
        for (int d=0; d<3; d++){
            x[d] = (1. - c->w)*x[d] + c->w*(qx[d] + c->g[d] + c->gq[d]);
            v[d] = (1. - c->w)*v[d] + c->w*(qv[d] + c->gv[d] + c->gqv[d]);
            a[d] = (1. - c->w)*a[d] + c->w*st->end[c->q].a[d];
        }
    }
}

// centre_start's position alone (the same operations).
static void centre_start_position(const struct centre_ref* c, const struct pfvi_state* st, double x[3]){
    const struct reb_particle* const pp = &st->start[c->p];
    const double px[3] = {pp->x, pp->y, pp->z};
    for (int d=0; d<3; d++){
        x[d] = px[d] + c->g[d];
    }
    if (c->q != SIZE_MAX){
        const struct reb_particle* const pq = &st->start[c->q];
        const double qx[3] = {pq->x, pq->y, pq->z};
        for (int d=0; d<3; d++){
            x[d] = (1. - c->w)*x[d] + c->w*(qx[d] + c->g[d] + c->gq[d]);
        }
    }
}

// The units of a step: each particle's kind, the pair its partner may be
// in, and an order in which every body comes after what it is corrected
// about (a cycle longer than a pair is cut where the chain closes: that
// body then goes without its centre's correction).
static void newton_order(struct pfvi_state* st, size_t N, const struct pfvi_field* field){
    struct pfvi_newton* const nw = st->newton;
    size_t* const order = st->newton_order;
    unsigned char* const mark = st->newton_mark;   // 0: not placed, 1: on the chain, 2: placed
    for (size_t i=0; i<N; i++){
        const struct pfvi_partner* const pi = &st->partners[i];
        const size_t p = pi->j;
        nw[i].partner = p;
        nw[i].companion = SIZE_MAX;
        mark[i] = 0;
        if (p == SIZE_MAX || !st->solve_form[i] || !st->solve_form[p]){
            nw[i].kind = PFVI_NEWTON_NONE;
        }else if (st->partners[p].j == i && st->partners[p].image == field->n_images - 1 - pi->image
                && st->solve_form[i] == st->solve_form[p] && st->solve_form[i]->u2 == 0.){
            nw[i].kind = (i < p) ? PFVI_NEWTON_PAIR : PFVI_NEWTON_MEMBER;
        }else{
            nw[i].kind = PFVI_NEWTON_SINGLE;
        }
    }
    for (size_t i=0; i<N; i++){
        const size_t p = nw[i].partner;
        // (Only a pair bound more tightly than i is to p: i orbits it as a whole.)
        if (nw[i].kind == PFVI_NEWTON_SINGLE && (nw[p].kind == PFVI_NEWTON_PAIR || nw[p].kind == PFVI_NEWTON_MEMBER)
                && nw[p].partner != i && st->partners[p].stiffness > st->partners[i].stiffness
                && st->start[p].m + st->start[nw[p].partner].m > 0.){
            nw[i].companion = nw[p].partner;
        }
    }
    size_t placed = 0;
    size_t* const stack = st->newton_index;
    for (size_t i=0; i<N; i++){
        // Follow i's chain (its partner, a pair member's leader) to a placed
        // body, a pair's leader or its end; place it from the far end.
        size_t chain = 0, j = i;
        while (mark[j] == 0){
            mark[j] = 1;
            stack[chain++] = j;
            if (nw[j].kind != PFVI_NEWTON_SINGLE && nw[j].kind != PFVI_NEWTON_MEMBER){
                break;
            }
            j = nw[j].partner;
        }
        while (chain > 0){
            const size_t k = stack[--chain];
            mark[k] = 2;
            order[placed++] = k;
        }
    }
    // From here on newton_index is each body's place in the order.
    for (size_t o=0; o<N; o++){
        st->newton_index[order[o]] = o;
    }
}

// Whether body i's centre was placed before it (its correction and
// predicted path are then known when i's are made).
static int centre_first(const struct pfvi_state* st, const struct centre_ref* c, size_t i){
    const size_t* const index = st->newton_index;
    return index[c->p] < index[i] && (c->q == SIZE_MAX || index[c->q] < index[i]);
}

int pfvi_newton_prepare(struct pfvi_state* st, size_t N, const struct pfvi_field* field){
    int factored = 1;
    for (size_t i=0; i<N; i++){
        struct pfvi_newton* const u = &st->newton[i];
        if (u->kind == PFVI_NEWTON_NONE || u->kind == PFVI_NEWTON_MEMBER){
            continue;
        }
        const size_t p = u->partner;
        const struct pfvi_solve_form* const f = st->solve_form[i];
        const int pair = (u->kind == PFVI_NEWTON_PAIR);
        const struct centre_ref c = centre_of(st, field, i);
        // A pair's relative coordinate feels G (m_i + m_p); a body its centre's G M.
        const double mu = field->G*(pair ? st->start[i].m + st->start[p].m : c.mass);
        double n[PFVI_STAGES_MAX][3], alpha[PFVI_STAGES_MAX];
        for (int k=1; k<=f->k_last; k++){
            double xc[3], r[3];
            centre_point(&c, (const double (*)[PFVI_STAGES_MAX][3])st->solve_x, k, xc);
            for (int d=0; d<3; d++){
                r[d] = st->solve_x[i][k][d] - xc[d];
            }
            const double r2 = (r[0]*r[0] + r[1]*r[1] + r[2]*r[2]) + field->softening2;
            const double inv = 1./sqrt(r2);
            alpha[k] = mu*inv*inv*inv;
            n[k][0] = r[0]*inv; n[k][1] = r[1]*inv; n[k][2] = r[2]*inv;
            if (!isfinite(alpha[k]) || !isfinite(n[k][0] + n[k][1] + n[k][2])){
                alpha[k] = 0.;
                n[k][0] = n[k][1] = n[k][2] = 0.;
            }
        }
        if (!newton_factor(f, (const double (*)[3])n, alpha, u)){
            // (a step far beyond the pair's time scale): the plain round
            u->kind = PFVI_NEWTON_NONE;
            factored = 0;
            if (pair){
                st->newton[p].kind = PFVI_NEWTON_NONE;
            }
        }
    }
    return factored;
}

// One unit's correction (body i of the real order) on the iterates y -> yn
// of the particles at index base + i (base 0: the real ones; a variational
// set's first; with alone, a test particle's variation at index `alone`,
// corrected without its centre's).
static void newton_correct_unit(struct pfvi_state* st, size_t i, const double (*y)[PFVI_STAGES_MAX-1][3],
        double (*yn)[PFVI_STAGES_MAX-1][3], size_t base, size_t alone){
    const struct pfvi_newton* const u = &st->newton[i];
    if (u->kind == PFVI_NEWTON_NONE || u->kind == PFVI_NEWTON_MEMBER){
        return;   // the plain round (members: with their pair)
    }
    const struct pfvi_solve_form* const f = st->solve_form[i];
    const int m = f->m;
    const size_t p = u->partner;
    const size_t vi = (alone != SIZE_MAX) ? alone : base + i;
    double b[PFVI_STAGES_MAX-1][3];
    if (u->kind == PFVI_NEWTON_PAIR){
        if (alone != SIZE_MAX){
            return;   // (a pair's member has no variation alone)
        }
        // Relative coordinate by Newton, barycentre by the round.
        const size_t vp = base + p;
        const double mi = st->start[i].m, mp = st->start[p].m, M = mi + mp;
        for (int l=0; l<m; l++){
            for (int c=0; c<3; c++){
                b[l][c] = (yn[vi][l][c] - y[vi][l][c]) - (yn[vp][l][c] - y[vp][l][c]);
            }
        }
        newton_apply(f, u, b);
        // The rows' 3 m values are contiguous: four at a time in vector
        // lanes, each lane the scalar expression below (the same bits),
        // then the rest one by one.
        double* const yni = &yn[vi][0][0];
        double* const ynp = &yn[vp][0][0];
        const double* const yi = &y[vi][0][0];
        const double* const yp = &y[vp][0][0];
        const double* const bb = &b[0][0];
        const int n = 3*m;
        int e = 0;
        if (M > PFVI_MASS_TINY){
#define ALL(x) ((pfvi_lanes){(x), (x), (x), (x)})
            const pfvi_lanes MI = ALL(mi), MP = ALL(mp), MM = ALL(M), WP = ALL(mp/M), WI = ALL(mi/M);
#undef ALL
            for (; e + 4 <= n; e+=4){
                pfvi_lanes a_i, a_p, x_i, x_p, B;
                memcpy(&a_i, yni + e, sizeof(a_i));
                memcpy(&a_p, ynp + e, sizeof(a_p));
                memcpy(&x_i, yi + e, sizeof(x_i));
                memcpy(&x_p, yp + e, sizeof(x_p));
                memcpy(&B, bb + e, sizeof(B));
                const pfvi_lanes bi = a_i - x_i, bp = a_p - x_p;
                const pfvi_lanes cm = (MI*bi + MP*bp)/MM;
                const pfvi_lanes ni = x_i + (cm + WP*B), np = x_p + (cm - WI*B);
                memcpy(yni + e, &ni, sizeof(ni));
                memcpy(ynp + e, &np, sizeof(np));
            }
        }
        for (; e<n; e++){
            const double bi = yni[e] - yi[e], bp = ynp[e] - yp[e];
            // Tiny masses: as mass fractions (m*b underflows; PFVI_MASS_TINY).
            const double cm = (M > PFVI_MASS_TINY) ? (mi*bi + mp*bp)/M : (mi/M)*bi + (mp/M)*bp;
            yni[e] = yi[e] + (cm + (mp/M)*bb[e]);
            ynp[e] = yp[e] + (cm - (mi/M)*bb[e]);
        }
        return;
    }
    for (int l=0; l<m; l++){
        for (int c=0; c<3; c++){
            b[l][c] = yn[vi][l][c] - y[vi][l][c];
        }
    }
    if (alone == SIZE_MAX && st->newton_index[p] < st->newton_index[i]
            && (u->companion == SIZE_MAX || st->newton_index[u->companion] < st->newton_index[i])){
        // The centre's correction, final in this round: it was placed first.
        // (Its bodies share one form when they are a pair; alone, p has its own.)
        double Dc[PFVI_STAGES_MAX-1][3];
        const struct pfvi_solve_form* const fp = st->solve_form[p];
        const size_t q = u->companion;
        const double w = (q == SIZE_MAX) ? 0. : st->start[q].m/(st->start[p].m + st->start[q].m);
        for (int l=0; l<fp->m; l++){
            for (int c=0; c<3; c++){
                const double dp = yn[base + p][l][c] - y[base + p][l][c];
                Dc[l][c] = (q == SIZE_MAX) ? dp : (1. - w)*dp + w*(yn[base + q][l][c] - y[base + q][l][c]);
            }
        }
        newton_cross(f, u, fp, (const double (*)[3])Dc, b);
    }
    newton_apply(f, u, b);
    for (int l=0; l<m; l++){
        for (int c=0; c<3; c++){
            yn[vi][l][c] = y[vi][l][c] + b[l][c];
        }
    }
}

void pfvi_newton_correct(struct pfvi_state* st, size_t N, const double (*y)[PFVI_STAGES_MAX-1][3],
        double (*yn)[PFVI_STAGES_MAX-1][3]){
    for (size_t o=0; o<N; o++){
        newton_correct_unit(st, st->newton_order[o], y, yn, 0, SIZE_MAX);
    }
}

void pfvi_newton_correct_variational(struct pfvi_state* st, size_t N){
    const double (*y)[PFVI_STAGES_MAX-1][3] = (const double (*)[PFVI_STAGES_MAX-1][3])st->var_unknowns;
    double (*yn)[PFVI_STAGES_MAX-1][3] = st->var_unknowns_next;
    for (size_t set=0; set<st->var_sets_N; set++){
        for (size_t o=0; o<N; o++){
            newton_correct_unit(st, st->newton_order[o], y, yn, st->var_sets[set], SIZE_MAX);
        }
    }
    if (st->var_sets_N*N < st->var_N){
        // Test particles' variations (each alone: no other body's varies).
        for (size_t v=0; v<st->var_N; v++){
            int in_set = 0;
            for (size_t set=0; set<st->var_sets_N; set++){
                in_set |= (v >= st->var_sets[set] && v < st->var_sets[set] + N);
            }
            if (!in_set){
                newton_correct_unit(st, st->var_real[v], y, yn, 0, v);
            }
        }
    }
}

/* ------------------------------------------------ the rounds and their stop */

PFVI_VECTOR_CLONES
double pfvi_solve_change(const double (*y)[3], const double (*yn)[3], const double* q0, int increment, int s,
        double scale){
    double diff = 0.;
    for (int c=0; c<3; c++){
        const double q = fabs(q0[c]), d = fabs(y[increment][c]);
        scale = (q > scale) ? q : scale;
        scale = (d > scale) ? d : scale;
    }
    // The largest difference, four at a time (the rows' 3 (s - 1) values
    // are contiguous): the largest of a set is the same in any order. A
    // difference that is not a number is found beside it; then the scalar
    // loop below gives the result (its sum carries that NaN through).
    const double* const a = &y[0][0];
    const double* const b = &yn[0][0];
    const int n = 3*(s - 1);
    const pfvi_lane_mask magnitude = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
    pfvi_lanes most = {0., 0., 0., 0.};
    pfvi_lane_mask nan = {0, 0, 0, 0};
    int l = 0;
    for (; l + 4 <= n; l+=4){
        pfvi_lanes x, xn;
        memcpy(&x, a + l, sizeof(x));
        memcpy(&xn, b + l, sizeof(xn));
        const pfvi_lanes d = (pfvi_lanes)((pfvi_lane_mask)(xn - x) & magnitude);   // fabs: the sign bit cleared
        most = lanes_where(d > most, d, most);
        nan |= (d != d);
    }
    double lanes[4];
    memcpy(lanes, &most, sizeof(lanes));
    int finite = ((nan[0] | nan[1]) | (nan[2] | nan[3])) == 0;
    for (int k=0; k<4; k++){
        diff = (lanes[k] > diff) ? lanes[k] : diff;
    }
    for (; l<n; l++){
        const double d = fabs(b[l] - a[l]);
        diff = (d > diff) ? d : diff;
        finite &= (d == d);
    }
    if (!finite){
        // (the largest difference, and their sum only to carry a NaN through)
        double any = 0.;
        for (int j=0; j<s-1; j++){
            for (int c=0; c<3; c++){
                const double d = fabs(yn[j][c] - y[j][c]);
                diff = (d > diff) ? d : diff;
                any += d;
            }
        }
        diff = (any == any) ? diff : any;
    }
    return (scale > 0.) ? diff/scale : diff;
}

// Each body's length scale for its change: its distance from its centre at
// the step's start (0 without one; the change is taken relative to the
// larger of it, |q_k| and the step). Round-off in the forces on a body is of
// that distance times the doubles' resolution: a star at 1e-3 AU from the
// barycentre, its planet at 1 AU, need not have its position converged to
// 1e-19 AU, which the forces do not resolve (and a body exactly at the
// origin, the centre of a symmetric ring, to 0).
static void solve_scales(struct pfvi_state* st, size_t N, const struct pfvi_field* field){
    for (size_t i=0; i<N; i++){
        st->solve_scale[i] = 0.;
        if (st->newton[i].partner == SIZE_MAX){
            continue;
        }
        const struct centre_ref c = centre_of(st, field, i);
        double xc[3];
        centre_start_position(&c, st, xc);
        const struct reb_particle* const p = &st->start[i];
        const double r[3] = {fabs(p->x - xc[0]), fabs(p->y - xc[1]), fabs(p->z - xc[2])};
        const double largest = fmax(r[0], fmax(r[1], r[2]));
        st->solve_scale[i] = isfinite(largest) ? largest : 0.;
    }
}

// The largest relative change of the real particles' unknowns (a NaN is kept).
static double change_of(const struct pfvi_state* st, size_t N){
    const int s = st->rule.s;
    double change = 0.;
    for (size_t i=0; i<N; i++){
        const double relative = pfvi_solve_change((const double (*)[3])st->unknowns[i],
                (const double (*)[3])st->unknowns_next[i], st->stage_start[i].q0, st->solve_form[i]->increment, s,
                st->solve_scale[i]);
        change = (relative > change || relative != relative) ? relative : change;
    }
    return change;
}

enum pfvi_solve_next pfvi_solve_verdict(double change, double previous, int stalled, int last_round){
    if (!isfinite(change)){
        return PFVI_SOLVE_FAILED;
    }
    if (change == 0.){
        return PFVI_SOLVE_CONVERGED;
    }
    const double theta = change/previous;
    if (theta >= 1.){
        // Not falling: the round-off floor if it is there, else diverging.
        // A floor above the confirming round's bound must hold for two
        // rounds: a single stall there can be a lag the corrections do not
        // model (with velocity-dependent forces the stage velocities follow
        // the positions a round late, and a drag's one stall at 5e-14, taken
        // as the floor, cost 1e-10 in 10 orbits; docs/solve.md).
        if (change <= PFVI_SOLVE_CONFIRM || (stalled && change <= PFVI_ITERATION_TOLERANCE)){
            return PFVI_SOLVE_CONVERGED;
        }
        return (change <= PFVI_ITERATION_TOLERANCE && !last_round) ? PFVI_SOLVE_STALLED
            : (last_round ? PFVI_SOLVE_FAILED : PFVI_SOLVE_DIVERGING);
    }
    if (last_round){
        return (change <= PFVI_ITERATION_TOLERANCE) ? PFVI_SOLVE_CONVERGED : PFVI_SOLVE_FAILED;
    }
    // What the iterates still have to go after the correction just made, if
    // they keep converging at theta: theta/(1 - theta) change.
    return (isfinite(previous) && theta*change <= PFVI_SOLVE_RESOLUTION*(1. - theta))
        ? PFVI_SOLVE_FINAL : PFVI_SOLVE_ITERATE;
}

void pfvi_solve_swap(struct pfvi_state* st){
    double (*swap)[PFVI_STAGES_MAX-1][3] = st->unknowns;
    st->unknowns = st->unknowns_next;
    st->unknowns_next = swap;
    swap = st->var_unknowns;
    st->var_unknowns = st->var_unknowns_next;
    st->var_unknowns_next = swap;
}

// The converged solve's end increment, for the classical form: the
// IIIA-IIIB update itself, h v_k + h sum_j (1 - c_j) hb_j A^j, from the
// forces at the stage points of y, the iterate whose forces the last round
// evaluated, rounded once. y's own end y[s-2] is a Newton correction's
// result: where that correction fell below the doubles' last place it was
// rounded away, and what it left is the same in every step of a steady orbit
// (the partner model's error on the iterate before), so taking it biased the
// energy (docs/roundoff.md: a circular orbit's fell by 1e-19 a step, 11
// standard errors of an ensemble over 3e4 orbits). The round's own G(y) has
// no such rest but three roundings of terms larger than the increment (h v_k
// and h times the sum); here h v_k and h sum are exact pairs, so that the
// increment is the update rounded once, and what that rounding loses joins
// the position's carried low-order part (end_low, then the compensation of
// the step taken). The interior stages stay y's (measured: taking G(y)'s
// for them alone left the bias; for them too, with their forces carried by
// the partners' tidal tensors, removed it no better). The end's force is
// evaluated after, at the new end (no round evaluated it). (The three components
// are the lanes of one vector, the fourth a copy of z, never stored; each
// lane is the scalar operation, so every build gives the same bits; the
// products are split as Dekker's, with no fused multiply-add.)
PFVI_VECTOR_CLONES
static void solve_take_end(struct pfvi_state* st, size_t N, double h){
    const int s = st->rule.s;
    const struct pfvi_lobatto* const rule = &st->rule;
    double hb[PFVI_STAGES_MAX];   // h w_j, as the rounds form it
    for (int j=0; j<s-1; j++){
        hb[j] = h*rule->w[j];
    }
    const double split = 134217729.;   // 2^27 + 1
    const double ch = split*h, h_hi = ch - (ch - h), h_lo = h - h_hi;
    const pfvi_lanes H = {h, h, h, h}, H_hi = {h_hi, h_hi, h_hi, h_hi}, H_lo = {h_lo, h_lo, h_lo, h_lo};
    const pfvi_lanes SPLIT = {split, split, split, split};
    for (size_t i=0; i<N; i++){
        if (!st->stage_fit[i].classical){
            continue;
        }
        const double (*const a)[3] = (const double (*)[3])st->stage_a[i];
        pfvi_lanes sum = {0., 0., 0., 0.};   // (row s - 1 of the round's sums, in its order)
        for (int j=0; j<s-1; j++){
            const double nu = rule->nu[s-1][j], hbj = hb[j];
            const pfvi_lanes A = {a[j][0], a[j][1], a[j][2], a[j][2]};
            sum += (pfvi_lanes){nu, nu, nu, nu}*((pfvi_lanes){hbj, hbj, hbj, hbj}*A);
        }
        const double* const v = st->stage_start[i].v0;
        const pfvi_lanes V = {v[0], v[1], v[2], v[2]};
        // h v = hv + hv_lo and h sum = hs + hs_lo exactly (Dekker's product)
        const pfvi_lanes cv = SPLIT*V, v_hi = cv - (cv - V), v_lo = V - v_hi;
        const pfvi_lanes hv = H*V;
        const pfvi_lanes hv_lo = ((H_hi*v_hi - hv) + H_hi*v_lo + H_lo*v_hi) + H_lo*v_lo;
        const pfvi_lanes cs = SPLIT*sum, s_hi = cs - (cs - sum), s_lo = sum - s_hi;
        const pfvi_lanes hs = H*sum;
        const pfvi_lanes hs_lo = ((H_hi*s_hi - hs) + H_hi*s_lo + H_lo*s_hi) + H_lo*s_lo;
        // hv + hs = total + total_lo exactly (Knuth's sum)
        const pfvi_lanes total = hv + hs, bb = total - hv;
        const pfvi_lanes total_lo = (hv - (total - bb)) + (hs - bb);
        const pfvi_lanes low = total_lo + (hv_lo + hs_lo);
        const pfvi_lanes update = total + low;
        const pfvi_lanes rest = (total - update) + low;
        double u[4], r[4];
        memcpy(u, &update, sizeof(u));
        memcpy(r, &rest, sizeof(r));
        double* const end = st->unknowns[i][s-2];
        end[0] = u[0]; end[1] = u[1]; end[2] = u[2];
        st->end_low[i][0] = r[0]; st->end_low[i][1] = r[1]; st->end_low[i][2] = r[2];
    }
}

// A force evaluation of the solve failed (rolled back). A force that is not
// finite at an iterate's stage point, or a stage point that overflowed, is
// this trial's failure, not the run's: the first iterate can lie far off
// the step's orbit (REBOUNDx's gr, whose own iteration diverges as its A
// nears 1, gave inf there at e = 0.84 with c = 30 where the halved step
// went on and ended 2.6e-8 from IAS15 at epsilon 1e-12). The step is then
// halved, as for a solve that did not converge: a shorter step's stages lie
// nearer its start, whose force was finite. Any other failure refuses. Said
// once per simulation, so that a force that is not finite by mistake (a
// callback's NaN) is not passed over in silence.
static enum pfvi_trial solve_forces_failed(struct reb_simulation* r, struct pfvi_state* st){
    // (Fixed steps, epsilon = 0, have no shorter step to take.)
    if ((st->fault.kind != PFVI_FAULT_FORCE && st->fault.kind != PFVI_FAULT_OVERFLOW) || !(st->options.epsilon > 0.)){
        return PFVI_TRIAL_ERROR;
    }
    st->stage_fault = st->fault;
    st->fault.kind = PFVI_FAULT_NONE;
    st->trial.stage_failed = 1;
    if (!st->stage_fault_warned){
        st->stage_fault_warned = 1;
        const int force = (st->stage_fault.kind == PFVI_FAULT_FORCE);
        pfvi_warning(r, "pfvi: the %s of particle %zu was not finite at a trial step's stage point "
                "(t = %.17g); retaken shorter (n_solve_halved), which can step across a thin region where it "
                "is not. Said once per simulation.",
                force ? "force" : "position or velocity", st->stage_fault.particle,
                force ? st->stage_fault.t : st->stage_fault.t0);
    }
    return PFVI_TRIAL_NOT_CONVERGED;
}

enum pfvi_trial pfvi_solve_stages(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        const struct pfvi_solve_ops* ops, int predicted){
    const int s = st->rule.s;
    struct pfvi_field field;
    if (!pfvi_field_of(r, st, &field)){
        pfvi_roll_back(r, st, N, t0);
        return PFVI_TRIAL_ERROR;
    }
    // The end stage's force acts on no stage of its own step (the classical
    // form): it is evaluated once, at the accepted end. So too with
    // velocity-dependent forces: the stage velocities are made from the
    // interior stages' forces alone (classical_velocities). (Taking the end
    // from the iterate there, as until 2026-11-29, biased the energy: the
    // Moon about the Earth drifted 2 m in 10 yr at epsilon 1e-12 under
    // REBOUNDx's gr, whatever c; docs/roundoff.md.)
    int end_free = 1;
    for (size_t i=0; end_free && i<N; i++){
        end_free = (st->solve_form[i]->k_last < s - 1);
    }
    for (size_t i=0; i<N; i++){
        st->end_low[i][0] = st->end_low[i][1] = st->end_low[i][2] = 0.;
    }
    newton_order(st, N, &field);
    solve_scales(st, N, &field);
    if (predicted != PFVI_PREDICTED_RETRY){
        pfvi_solve_predict(st, N, &field, h, predicted == PFVI_PREDICTED_EXTRAPOLATED, !pfvi_gravity_two_alone(r, N));
        ops->start_at(st, N);
    }
    ops->positions(st, N, h);
    if (!pfvi_newton_prepare(st, N, &field)){
        st->trial.solve_recovered = 1;
    }
    int rounds = 0, final = 0, newton = 1, diverged = 0, converged = 0, end_evaluated = 0, stalled = 0;
    double previous = INFINITY, change = INFINITY, residual = INFINITY;
    for (;;){
        // (an end free of its step is evaluated once, after: solve_take_end)
        const int k_last = end_free ? s - 2 : s - 1;
        if (!ops->forces(r, st, N, t0, h, 1, k_last)){
            return solve_forces_failed(r, st);
        }
        rounds++;
        end_evaluated = (k_last == s - 1);
        ops->round(st, N, h);
        // The round's own change (the residual) is needed to confirm a final
        // iterate, at the round-off floor and without Newton; otherwise the
        // correction's change says everything (a NaN passes through it).
        residual = (final || !newton) ? change_of(st, N) : NAN;
        if (residual == 0. || (final && residual <= PFVI_SOLVE_CONFIRM)){
            converged = 1;
            if (st->var_N){
                // The variational particles' round corrected as every
                // round's is: their own solve goes on from it.
                pfvi_newton_correct_variational(st, N);
                ops->variational_change(st);
            }
            break;
        }
        if (!newton && !isfinite(residual)){
            break;
        }
        final = 0;
        if (newton){
            pfvi_newton_correct(st, N, (const double (*)[PFVI_STAGES_MAX-1][3])st->unknowns, st->unknowns_next);
            change = change_of(st, N);
        }else{
            change = residual;
        }
        if (st->var_N){
            // (the variational particles' Jacobian is the real one's, refreshed or not)
            pfvi_newton_correct_variational(st, N);
            ops->variational_change(st);
        }
        const enum pfvi_solve_next next = pfvi_solve_verdict(change, previous, stalled, rounds >= PFVI_ITERATION_MAX);
        stalled = (next == PFVI_SOLVE_STALLED);
        if (next == PFVI_SOLVE_FAILED){
            break;
        }
        if (next == PFVI_SOLVE_CONVERGED && newton){
            // (at the round-off floor the correction is the residual's size)
            residual = change;
        }
        if (next == PFVI_SOLVE_CONVERGED && residual <= PFVI_ITERATION_TOLERANCE){
            // At the round-off floor: the iterate the forces were evaluated at.
            converged = 1;
            break;
        }
        pfvi_solve_swap(st);
        previous = change;
        final = (next == PFVI_SOLVE_FINAL);
        if (next == PFVI_SOLVE_DIVERGING){
            // A growing change: the Jacobians afresh at this iterate, then
            // the plain round; a third time, the solve has failed.
            st->trial.solve_recovered = 1;
            previous = INFINITY;
            diverged++;
            if (diverged == 1 && newton){
                ops->positions(st, N, h);
                pfvi_newton_prepare(st, N, &field);
            }else if (diverged <= 2){
                newton = 0;
            }else{
                break;
            }
        }
    }
    st->trial.rounds = (uint64_t)rounds;
    st->trial.change = isnan(residual) ? change : residual;  // (what the last round measured)
    // Where the end's force enters no stage (the classical form) the end is
    // the update's (solve_take_end), and no round has evaluated its force.
    if (converged && end_free){
        solve_take_end(st, N, h);
    }
    if (converged && !end_evaluated && !ops->forces(r, st, N, t0, h, s - 1, s - 1)){
        return solve_forces_failed(r, st);
    }
    return converged ? PFVI_TRIAL_OK : PFVI_TRIAL_NOT_CONVERGED;
}

/* -------------------------------------------------- the two-body predictor */

// Stumpff's functions c0 .. c3 of x = beta s^2 (beta = 2 mu/r - v^2).
static inline __attribute__((always_inline)) void stumpff(double x, double c[4]){
    if (fabs(x) < PFVI_STUMPFF_SERIES){
        // Series to x^6: below 1e-16 relative for |x| < 0.1 (Horner in x,
        // the coefficients (-1)^k/(2k + 3)! and (-1)^k/(2k + 2)!).
        c[3] = 1./6. + x*(-1./120. + x*(1./5040. + x*(-1./362880. + x*(1./39916800.
            + x*(-1./6227020800. + x*(1./1307674368000.))))));
        c[2] = 1./2. + x*(-1./24. + x*(1./720. + x*(-1./40320. + x*(1./3628800.
            + x*(-1./479001600. + x*(1./87178291200.))))));
        c[1] = 1. - x*c[3];
        c[0] = 1. - x*c[2];
        return;
    }
    if (x > 0.){
        const double r = sqrt(x);
        c[0] = cos(r);
        c[1] = sin(r)/r;
    }else{
        const double r = sqrt(-x);
        c[0] = cosh(r);
        c[1] = sinh(r)/r;
    }
    c[2] = (1. - c[0])/x;
    c[3] = (1. - c[1])/x;
}

// The two-body orbit of (r0, v0) about mu in universal variables, kept
// between the stages of one step: each stage starts from the last point
// drawn, its anomaly s and the functions G_n(s) = s^n c_n(beta s^2) there,
// and reaches its own by the G's addition theorems over the short stretch
// between them (no sine or cosine where that stretch is short).
struct kepler_orbit_uv {
    double r0n, eta, beta, mu, mu_r0;
    double k;                   // mu - beta r0n: d^2 r/ds^2 = k G0 - beta eta G1
    double s, t;                // the last point drawn: its anomaly and time
    double G0, G1, G2, G3;      // G_n(s) there
    double r, dr, ddr;          // the radius there, d r/ds and d^2 r/ds^2
};

static int kepler_start(const double r0[3], const double v0[3], double mu, struct kepler_orbit_uv* o){
    o->r0n = sqrt(r0[0]*r0[0] + r0[1]*r0[1] + r0[2]*r0[2]);
    o->eta = r0[0]*v0[0] + r0[1]*v0[1] + r0[2]*v0[2];
    o->beta = 2.*mu/o->r0n - (v0[0]*v0[0] + v0[1]*v0[1] + v0[2]*v0[2]);
    o->mu = mu;
    o->mu_r0 = mu/o->r0n;
    o->k = mu - o->beta*o->r0n;
    o->s = 0.;
    o->t = 0.;
    o->G0 = 1.; o->G1 = 0.; o->G2 = 0.; o->G3 = 0.;
    o->r = o->r0n;
    o->dr = o->eta;
    o->ddr = o->k;
    return o->r0n > 0. && mu > 0. && isfinite(o->beta) && isfinite(o->eta) && isfinite(o->mu_r0);
}

// G_n at the anomaly `last + d` from G_n at `last` (the addition theorems
// of the universal functions, beta and d's own G_n), or from Stumpff's
// functions at s = last + d where d is too long for their short series.
static void kepler_functions(const struct kepler_orbit_uv* o, double d, double s, double G[4]){
    const double x = o->beta*d*d;
    if (fabs(x) < PFVI_STUMPFF_SERIES){
        double c[4];
        stumpff(x, c);
        const double d2 = d*d;
        const double g1 = d*c[1], g2 = d2*c[2], g3 = (d2*d)*c[3];
        const double g0 = c[0];
        G[0] = o->G0*g0 - o->beta*(o->G1*g1);
        G[1] = o->G1*g0 + o->G0*g1;
        G[2] = (o->G2*g0 + o->G1*g1) + g2;
        G[3] = (o->G3 + g3) + (o->G2*g1 + o->G1*g2);
        return;
    }
    double c[4];
    stumpff(o->beta*s*s, c);
    G[0] = c[0]; G[1] = s*c[1]; G[2] = s*s*c[2]; G[3] = s*s*s*c[3];
}

// The point t after the start: Kepler's equation r0 G1 + eta G2 + mu G3 = t
// solved by Halley's method from s(t)'s Taylor series to the cube about the
// last point drawn (ds/dt = 1/r, d^2s/dt^2 = -r'/r^3, d^3s/dt^3 =
// (3 r'^2 - r r'')/r^5, primes in s); 0 if it did not converge.
static int kepler_drift(const double r0[3], const double v0[3], struct kepler_orbit_uv* o, double t, double r[3]){
    const double ir = 1./o->r;
    const double u = (t - o->t)*ir, a = o->dr*ir;
    double d = u*(1. + u*(-0.5*a + u*((3.*a*a - o->ddr*ir)*(1./6.))));
    for (int it=0; it<PFVI_PREDICTOR_KEPLER_ITERATIONS; it++){
        const double s = o->s + d;
        double G[4];
        kepler_functions(o, d, s, G);
        const double F = o->r0n*G[1] + o->eta*G[2] + o->mu*G[3] - t;
        const double dF = o->r0n*G[0] + o->eta*G[1] + o->mu*G[2];   // the radius at s
        const double ddF = o->eta*G[0] + o->k*G[1];
        const double ds = F*dF/(dF*dF - 0.5*F*ddF);
        if (!isfinite(ds)){
            return 0;
        }
        if (fabs(ds) > PFVI_PREDICTOR_KEPLER_LAST*fabs(s)){
            d -= ds;
            continue;
        }
        // The last correction: G2 and G3 at s - ds by their series to the
        // cube (G3' = G2, G2' = G1, G1' = G0, G0' = -beta G1); the next
        // stage starts from s itself, whose G's are at hand, and its time.
        const double ds2 = 0.5*ds*ds, ds3 = ds2*ds*(1./3.);
        const double G3 = ((G[3] - G[2]*ds) + G[1]*ds2) - G[0]*ds3;
        const double G2 = ((G[2] - G[1]*ds) + G[0]*ds2) + o->beta*G[1]*ds3;
        const double f = 1. - o->mu_r0*G2, g = t - o->mu*G3;
        for (int c=0; c<3; c++){
            r[c] = f*r0[c] + g*v0[c];
        }
        o->s = s;
        o->t = t + F;
        o->G0 = G[0]; o->G1 = G[1]; o->G2 = G[2]; o->G3 = G[3];
        o->r = dF;
        o->dr = ddF;
        o->ddr = o->mu - o->beta*dF;
        return dF > 0.;
    }
    return 0;
}

// The two-body pull of the relative position r about mu (softened).
static void kepler_pull(const double r[3], double mu, double softening2, double a[3]){
    const double r2 = (r[0]*r[0] + r[1]*r[1] + r[2]*r[2]) + softening2;
    const double f = -mu/(r2*sqrt(r2));
    a[0] = f*r[0]; a[1] = f*r[1]; a[2] = f*r[2];
}

// What the predictor integrates beside the two-body orbit: at each stage
// j < s - 1 of this step, the acceleration a body (or a pair's relative
// coordinate, or its barycentre) feels beyond the pair's pull, extrapolated
// from the last step's stages (their Lagrange basis at this step's nodes),
// or held at its start value without them; and its integral over the step
// by the classical form's own stage formula, exact for the polynomial the
// rest follows: out[k] = h^2 sum_j nu[k][j] w_j rest_j. Extrapolation and
// integral are one matrix for all bodies of a step (rest_weights):
//     out[k] = h^2 (start[k] rest_0 + sum_m last[k][m] rest_old_m).
// (struct pfvi_rest_weights, pfvi.h: kept in the state for the last step ratio)

// The lanes k of last_t and start hold each sum in the scalar loop's order
// (j, then m, ascending), so the vector loops give the scalar loops' bits.
PFVI_VECTOR_CLONES
static void rest_weights_of(const struct pfvi_lobatto* rule, const double (*basis_t)[PFVI_STAGES_MAX],
        struct pfvi_rest_weights* rw){
    const int s = rule->s;
    rw->extrapolated = (basis_t != NULL);
    memset(rw->start, 0, sizeof(rw->start));
    for (int k=1; k<s; k++){
        double start = rule->nu[k][0]*rule->w[0];
        for (int j=1; !basis_t && j<s-1; j++){
            start += rule->nu[k][j]*rule->w[j];
        }
        rw->start[k] = start;
    }
    if (!basis_t){
        return;
    }
    pfvi_lanes nuw[PFVI_STAGES_MAX][2];   // nu[k][j] w_j, lanes k
    for (int j=1; j<s-1; j++){
        const pfvi_lanes w = {rule->w[j], rule->w[j], rule->w[j], rule->w[j]};
        memcpy(&nuw[j][0], &rule->nu_t[j][0], sizeof(nuw[j][0]));
        memcpy(&nuw[j][1], &rule->nu_t[j][4], sizeof(nuw[j][1]));
        nuw[j][0] *= w;
        nuw[j][1] *= w;
    }
    for (int m=0; m<PFVI_STAGES_MAX; m++){
        pfvi_lanes lo = {0., 0., 0., 0.}, hi = {0., 0., 0., 0.};
        for (int j=1; j<s-1; j++){
            const double b = basis_t[m][j];
            const pfvi_lanes bb = {b, b, b, b};
            lo += nuw[j][0]*bb;
            hi += nuw[j][1]*bb;
        }
        memcpy(&rw->last_t[m][0], &lo, sizeof(lo));
        memcpy(&rw->last_t[m][4], &hi, sizeof(hi));
    }
}

PFVI_VECTOR_CLONES
static void rest_integral(const struct pfvi_state* st, const struct pfvi_rest_weights* rw, double h,
        const double rest0[3], const double (*rest_old)[3], double (*out)[3]){
    const int s = st->rule.s;
    const int n_old = rw->extrapolated ? s : 0;   // (read once: the loop's bound, not a load per pass)
    const double h2 = h*h;
    pfvi_lanes start_lo, start_hi;
    memcpy(&start_lo, &rw->start[0], sizeof(start_lo));
    memcpy(&start_hi, &rw->start[4], sizeof(start_hi));
    for (int c=0; c<3; c++){
        const pfvi_lanes r0 = {rest0[c], rest0[c], rest0[c], rest0[c]};
        pfvi_lanes lo = start_lo*r0, hi = start_hi*r0;
        for (int m=0; m<n_old; m++){
            pfvi_lanes wl, wh;
            memcpy(&wl, &rw->last_t[m][0], sizeof(wl));
            memcpy(&wh, &rw->last_t[m][4], sizeof(wh));
            const pfvi_lanes r = {rest_old[m][c], rest_old[m][c], rest_old[m][c], rest_old[m][c]};
            lo += wl*r;
            hi += wh*r;
        }
        double sum[PFVI_STAGES_MAX];
        memcpy(sum, &lo, sizeof(lo));
        memcpy(sum + 4, &hi, sizeof(hi));
        for (int k=1; k<s; k++){
            out[k][c] = h2*sum[k];
        }
    }
}

// The path of body i over the step, as the predictor draws it: about its
// partner along their two-body orbit plus the integral of the rest of its
// acceleration; a mutual pair's relative orbit about their barycentre; the
// start's motion under its extrapolated acceleration without a partner.
static void predict_body(struct pfvi_state* st, const struct pfvi_field* field, size_t i, double h,
        const struct pfvi_rest_weights* rw){
    const int s = st->rule.s;
    const struct pfvi_newton* const u = &st->newton[i];
    if (u->kind == PFVI_NEWTON_MEMBER){
        return;   // drawn with its pair
    }
    const struct reb_particle* const pi = &st->start[i];
    const double* const ai = st->end[i].a;
    const double q0[3] = {pi->x, pi->y, pi->z}, v0[3] = {pi->vx, pi->vy, pi->vz};
    double (*x)[3] = st->solve_x[i];
    const size_t p = u->partner;
    double rest_old[PFVI_STAGES_MAX][3], drift[PFVI_STAGES_MAX][3];
    if (p == SIZE_MAX || !(field->G > 0.)){
        if (rw->extrapolated){
            memcpy(rest_old, st->predictor_a[i], sizeof(rest_old));
        }
        rest_integral(st, rw, h, ai, (const double (*)[3])rest_old, drift);
        for (int k=1; k<s; k++){
            const double t = st->rule.c[k]*h;
            for (int c=0; c<3; c++){
                x[k][c] = q0[c] + (t*v0[c] + drift[k][c]);
            }
        }
        return;
    }
    const int pair = (u->kind == PFVI_NEWTON_PAIR);
    const struct centre_ref cr = centre_of(st, field, i);
    double xc0[3], vc0[3], ac0[3];
    centre_start(&cr, st, xc0, vc0, ac0);
    double r0[3], w0[3];
    for (int c=0; c<3; c++){
        r0[c] = q0[c] - xc0[c];
        w0[c] = v0[c] - vc0[c];
    }
    const struct reb_particle* const pp = &st->start[p];
    const double mp = pair ? pp->m : cr.mass;
    const double M = pi->m + mp, mu = field->G*M;
    double pull[3], rest0[3];
    kepler_pull(r0, mu, field->softening2, pull);
    for (int c=0; c<3; c++){
        rest0[c] = (ai[c] - ac0[c]) - pull[c];
    }
    if (rw->extrapolated){
        for (int m=0; m<s; m++){
            double xc[3], r[3], a[3];
            centre_point(&cr, (const double (*)[PFVI_STAGES_MAX][3])st->predictor_x, m, xc);
            for (int c=0; c<3; c++){
                r[c] = st->predictor_x[i][m][c] - xc[c];
            }
            kepler_pull(r, mu, field->softening2, a);
            centre_point(&cr, (const double (*)[PFVI_STAGES_MAX][3])st->predictor_a, m, xc);
            for (int c=0; c<3; c++){
                // (centre_point adds the images' shifts: taken off again for an acceleration)
                const double ac = xc[c] - (cr.g[c] + cr.w*cr.gq[c]);
                rest_old[m][c] = (st->predictor_a[i][m][c] - ac) - a[c];
            }
        }
    }
    rest_integral(st, rw, h, rest0, (const double (*)[3])rest_old, drift);
    double cm_drift[PFVI_STAGES_MAX][3], cm0[3], cmv[3];
    // A pair's barycentre from mass fractions (a first iterate: no division
    // per component; and tiny masses, PFVI_MASS_TINY, need no branch).
    const double wi = pi->m/M, wp = mp/M;
    if (pair){
        const int n_old = rw->extrapolated ? s : 0;
        double cma0[3], cma_old[PFVI_STAGES_MAX][3];
        for (int c=0; c<3; c++){
            cm0[c] = wi*q0[c] + wp*xc0[c];
            cmv[c] = wi*v0[c] + wp*vc0[c];
            cma0[c] = wi*ai[c] + wp*ac0[c];
            for (int m=0; m<n_old; m++){
                cma_old[m][c] = wi*st->predictor_a[i][m][c] + wp*st->predictor_a[p][m][c];
            }
        }
        rest_integral(st, rw, h, cma0, (const double (*)[3])cma_old, cm_drift);
    }
    const int drawn = centre_first(st, &cr, i);
    struct kepler_orbit_uv orbit;
    int kepler = kepler_start(r0, w0, mu, &orbit);
    for (int k=1; k<s; k++){
        const double t = st->rule.c[k]*h;
        double r[3];
        kepler = kepler && kepler_drift(r0, w0, &orbit, t, r);
        if (!kepler){
            for (int c=0; c<3; c++){
                r[c] = r0[c] + t*(w0[c] + 0.5*t*pull[c]);
            }
        }
        for (int c=0; c<3; c++){
            r[c] += drift[k][c];
        }
        if (pair){
            double (*xp)[3] = st->solve_x[p];
            for (int c=0; c<3; c++){
                const double cm = cm0[c] + (t*cmv[c] + cm_drift[k][c]);
                x[k][c] = cm + wp*r[c];
                xp[k][c] = (cm - wi*r[c]) - cr.g[c];
            }
        }else{
            // About the centre's own predicted path (drawn first, unless a
            // cycle of partners put it after: then its Taylor path).
            double xc[3];
            if (drawn){
                centre_point(&cr, (const double (*)[PFVI_STAGES_MAX][3])st->solve_x, k, xc);
            }
            for (int c=0; c<3; c++){
                const double centre = drawn ? xc[c] : xc0[c] + t*(vc0[c] + 0.5*t*ac0[c]);
                x[k][c] = centre + r[c];
            }
        }
    }
}

// basis_t[m][j] = l_m(1 + rho c^j), the last step's Lagrange basis at this
// step's nodes, transposed (rows m < s; the others left as they are):
// pfvi_lagrange_at for every j at once, the nodes j as vector lanes, each
// lane its operations in its order (the same bits).
PFVI_VECTOR_CLONES
static void lagrange_basis(const struct pfvi_lobatto* rule, double rho, double (*basis_t)[PFVI_STAGES_MAX]){
#define ALL(x) ((pfvi_lanes){(x), (x), (x), (x)})
    const int s = rule->s;
    double tau[PFVI_STAGES_MAX] = {1., 1., 1., 1., 1., 1., 1., 1.};
    for (int j=0; j<s; j++){
        tau[j] = 1. + rho*rule->c[j];
    }
    pfvi_lanes t_lo, t_hi;
    memcpy(&t_lo, tau, sizeof(t_lo));
    memcpy(&t_hi, tau + 4, sizeof(t_hi));
    pfvi_lanes below_lo[PFVI_STAGES_MAX], below_hi[PFVI_STAGES_MAX];
    below_lo[0] = ALL(1.);
    below_hi[0] = ALL(1.);
    for (int n=1; n<s; n++){
        below_lo[n] = below_lo[n-1]*(t_lo - ALL(rule->c[n-1]));
        below_hi[n] = below_hi[n-1]*(t_hi - ALL(rule->c[n-1]));
    }
    pfvi_lanes above_lo = ALL(1.), above_hi = ALL(1.);
    for (int m=s-1; m>=0; m--){
        const pfvi_lanes lo = ALL(rule->lagrange[m])*(below_lo[m]*above_lo);
        const pfvi_lanes hi = ALL(rule->lagrange[m])*(below_hi[m]*above_hi);
        memcpy(&basis_t[m][0], &lo, sizeof(lo));
        memcpy(&basis_t[m][4], &hi, sizeof(hi));
        above_lo *= t_lo - ALL(rule->c[m]);
        above_hi *= t_hi - ALL(rule->c[m]);
    }
#undef ALL
}

void pfvi_solve_predict(struct pfvi_state* st, size_t N, const struct pfvi_field* field, double h, int extrapolate,
        int rest){
    // The last step's stages, in units of its length, at this step's nodes:
    // the same for the same s and step ratio, so made again only when either
    // changed since the last extrapolated step (the same inputs, the same
    // bits). Without a rest, weights of zero: nothing extrapolated, a drift
    // of zero.
    static const struct pfvi_rest_weights no_rest = {0};
    const struct pfvi_rest_weights* rw = &st->predict_weights;
    struct pfvi_rest_weights start_only;
    if (!rest){
        rw = &no_rest;
    }else if (extrapolate){
        const double rho = h/st->predictor_h;
        if (st->predict_weights_s != st->rule.s || memcmp(&rho, &st->predict_weights_rho, sizeof(rho)) != 0){
            double basis_t[PFVI_STAGES_MAX][PFVI_STAGES_MAX] = {{0.}};   // (rows zero beyond s: rest_weights_of reads every m)
            lagrange_basis(&st->rule, rho, basis_t);
            rest_weights_of(&st->rule, (const double (*)[PFVI_STAGES_MAX])basis_t, &st->predict_weights);
            st->predict_weights_s = st->rule.s;
            st->predict_weights_rho = rho;
        }
    }else{
        rest_weights_of(&st->rule, NULL, &start_only);
        rw = &start_only;
    }
    for (size_t o=0; o<N; o++){
        predict_body(st, field, st->newton_order[o], h, rw);
    }
}

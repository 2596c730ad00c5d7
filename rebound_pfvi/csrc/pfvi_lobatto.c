/**
 * pfvi_lobatto.c: the s-point discrete Lagrangian of seed section 6, its
 * quadrature and its fitted stage coefficients.
 *
 * Ld(q_k, q_k+1, delta q) = h sum_j w_j L(q^j, qdot^j) with Gauss-Lobatto
 * nodes c^j and weights w_j, and stage values
 *     q^j      = b^j q_k + bbar^j q_k+1 + delta q^j,
 *     h qdot^j = B^j q_k + Bbar^j q_k+1 + sum_l a^j_l delta q^l,
 * where delta q^1 = delta q^s = 0, b .. Bbar are the seed's coefficients
 * fitted to the oscillator at u = omega h (pfvi_fitting.c gives the same for
 * two nodes), and a^j_l is the differentiation matrix of the polynomial
 * through the nodes. With u = 0 this is the classical Lobatto (Galerkin)
 * discrete Lagrangian of Marsden & West (2001), of order 2s - 2.
 *
 * In closed form the seed's coefficients are
 *     b = sin((1-c)u)/sin u,       bbar = sin(cu)/sin u,
 *     B = -u cos((1-c)u)/sin u,    Bbar = u cos(cu)/sin u,
 * and the combinations the step needs without cancellation are
 *     beta_m = b + bbar - 1 = 2 sin(cu/2) sin((1-c)u/2) / cos(u/2),
 *     beta_d = B + Bbar     = -u sin((2c-1)u/2) / cos(u/2).
 */
#include <math.h>
#include <string.h>
#include "pfvi.h"

// Legendre P_n(x) and P_n'(x), by the three-term recurrence.
static void legendre(int n, long double x, long double* p, long double* dp){
    long double p0 = 1.L, p1 = x;
    if (n == 0){
        *p = 1.L; *dp = 0.L;
        return;
    }
    for (int k=1; k<n; k++){
        const long double p2 = ((2*k + 1)*x*p1 - k*p0)/(k + 1);
        p0 = p1;
        p1 = p2;
    }
    *p = p1;
    *dp = n*(p0 - x*p1)/(1.L - x*x);
}

// LU factorisation with partial pivoting of the m x m matrix in fit->lu; its
// determinant goes to *det (0 if a pivot vanishes).
static void stage_matrix_factor(int m, struct pfvi_stage_fit* fit, double* det){
    double d = 1.;
    for (int k=0; k<m; k++){
        int p = k;
        for (int i=k+1; i<m; i++){
            if (fabs(fit->lu[i][k]) > fabs(fit->lu[p][k])) p = i;
        }
        fit->pivot[k] = p;
        if (p != k){
            for (int j=0; j<m; j++){
                const double tmp = fit->lu[k][j]; fit->lu[k][j] = fit->lu[p][j]; fit->lu[p][j] = tmp;
            }
            d = -d;
        }
        const double pivot = fit->lu[k][k];
        d *= pivot;
        if (pivot == 0.){
            *det = 0.;
            return;
        }
        for (int i=k+1; i<m; i++){
            const double f = fit->lu[i][k]/pivot;
            fit->lu[i][k] = f;
            for (int j=k+1; j<m; j++){
                fit->lu[i][j] -= f*fit->lu[k][j];
            }
        }
    }
    *det = d;
}

// Coefficients, momentum normalisation and factorised matrix at u (u = 0: classical).
static void stage_fit_at(const struct pfvi_lobatto* q, double u, int phase, struct pfvi_stage_fit* fit, double* det){
    const int s = q->s;
    if (u == 0.){
        for (int k=0; k<s; k++){
            fit->b[k] = 1. - q->c[k]; fit->bbar[k] = q->c[k];
            fit->B[k] = -1.; fit->Bbar[k] = 1.;
            fit->beta_m[k] = 0.; fit->beta_d[k] = 0.;
        }
        fit->G = 1.;
    }else{
        const double sin_u = sin(u);
        const double u_over_sin_u = u/sin_u;
        const double cos_half = cos(0.5*u);
        double gamma_sum = 0.;
        for (int k=0; k<s; k++){
            const double c = q->c[k];
            const double sc = sin(c*u), cc = cos(c*u);
            const double sm = sin((1. - c)*u), cm = cos((1. - c)*u);
            fit->b[k] = sm/sin_u;
            fit->bbar[k] = sc/sin_u;
            fit->B[k] = -u_over_sin_u*cm;
            fit->Bbar[k] = u_over_sin_u*cc;
            fit->beta_m[k] = 2.*sin(0.5*c*u)*sin(0.5*(1. - c)*u)/cos_half;
            fit->beta_d[k] = -u*sin((c - 0.5)*u)/cos_half;
            gamma_sum += q->w[k]*cos((2.*c - 1.)*u);
        }
        // gamma_s(u): the rule applied to cos(2 omega (t - h/2)) over its
        // exact integral, the factor by which the printed Ld scales the
        // oscillator's exact discrete Lagrangian.
        fit->G = phase ? gamma_sum*u_over_sin_u : 1.;
    }
    // The equations -D1 Ld = G p_k (row 0) and dLd/d(delta q^j) = 0 (rows j),
    // linear in the unknowns (Delta = q_k+1 - q_k, delta q^j) for given stage
    // accelerations.
    const int m = s - 1;
    double row_B[PFVI_STAGES_MAX];  // multipliers of h qdot^k in each equation: w_k B^k, w_k a^k_j
    memset(fit->lu, 0, sizeof(fit->lu));
    for (int e=0; e<m; e++){
        for (int k=0; k<s; k++){
            row_B[k] = q->w[k]*(e == 0 ? fit->B[k] : q->a[k][e]);
        }
        double q0 = 0.;
        for (int k=0; k<s; k++){
            fit->lu[e][0] += row_B[k]*fit->Bbar[k];
            for (int l=1; l<m; l++){
                fit->lu[e][l] += row_B[k]*q->a[k][l];
            }
            q0 += row_B[k]*fit->beta_d[k];
        }
        fit->q0_row[e] = q0;
    }
    stage_matrix_factor(m, fit, det);
}

int pfvi_lobatto_compute(int s, struct pfvi_lobatto* q){
    if (s < PFVI_STAGES_MIN || s > PFVI_STAGES_MAX){
        return 0;
    }
    memset(q, 0, sizeof(*q));
    q->s = s;
    const int n = s - 1;
    // Nodes: x = -1, 1 and the roots of P_n' on [-1, 1], by Newton's method
    // from the Chebyshev-Lobatto points, using the Legendre equation for P_n''.
    long double x[PFVI_STAGES_MAX];
    x[0] = -1.L; x[n] = 1.L;
    for (int j=1; j<n; j++){
        long double xj = -cosl(M_PI*j/n);
        for (int it=0; it<100; it++){
            long double p, dp;
            legendre(n, xj, &p, &dp);
            const long double d2p = (2.L*xj*dp - n*(n + 1)*p)/(1.L - xj*xj);
            const long double dx = dp/d2p;
            xj -= dx;
            if (fabsl(dx) <= 1e-19L*fmaxl(1.L, fabsl(xj))) break;
        }
        x[j] = xj;
    }
    // Exact symmetry about the midpoint (the Lobatto rule is symmetric).
    for (int j=0; j<=n/2; j++){
        const long double mean = 0.5L*(x[n-j] - x[j]);
        x[j] = -mean; x[n-j] = mean;
    }
    long double lambda[PFVI_STAGES_MAX];
    for (int j=0; j<=n; j++){
        long double p, dp;
        legendre(n, x[j], &p, &dp);
        q->c[j] = (double)(0.5L*(1.L + x[j]));
        q->w[j] = (double)(1.L/(n*(n + 1)*p*p));  // 2/(n(n+1)P^2) on [-1, 1], halved for [0, 1]
        lambda[j] = 1.L;
        for (int m=0; m<=n; m++){
            if (m != j) lambda[j] /= 0.5L*(x[j] - x[m]);
        }
    }
    // Differentiation matrix from the barycentric weights; the diagonal makes
    // every row sum to zero (seed section 6, first condition).
    for (int k=0; k<=n; k++){
        long double diagonal = 0.L;
        for (int j=0; j<=n; j++){
            if (j == k) continue;
            const long double akj = (lambda[j]/lambda[k])/(0.5L*(x[k] - x[j]));
            q->a[k][j] = (double)akj;
            diagonal -= akj;
        }
        q->a[k][k] = (double)diagonal;
    }
    struct pfvi_stage_fit classical;
    stage_fit_at(q, 0., 0, &classical, &q->det_classical);
    return 1;
}

enum pfvi_fit_status pfvi_stage_fit(const struct pfvi_lobatto* q, double omega, double h,
        double u_max, int fitting, struct pfvi_stage_fit* fit){
    double u;
    const enum pfvi_fit_status status = pfvi_limit_u(&omega, h, u_max, &u);
    double det;
    stage_fit_at(q, u, fitting == PFVI_FITTING_PHASE, fit, &det);
    fit->omega = (u == 0.) ? 0. : omega;
    // Where the matrix is (nearly) singular q_k+1 is not determined by
    // (q_k, p_k); where G vanishes "phase" divides momenta by zero.
    if (!(fabs(det) >= PFVI_POLE_GUARD*fabs(q->det_classical)) || !(fabs(fit->G) >= PFVI_POLE_GUARD)){
        return PFVI_FIT_POLE;
    }
    return status;
}

int pfvi_lobatto_table(int s, double* c, double* w, double* a){
    struct pfvi_lobatto q;
    if (!pfvi_lobatto_compute(s, &q)){
        return 0;
    }
    for (int k=0; k<s; k++){
        c[k] = q.c[k];
        w[k] = q.w[k];
        for (int j=0; j<s; j++){
            a[k*s + j] = q.a[k][j];
        }
    }
    return 1;
}

double pfvi_gamma_stages(int s, double u){
    struct pfvi_lobatto q;
    if (!pfvi_lobatto_compute(s, &q)){
        return NAN;
    }
    struct pfvi_stage_fit fit;
    double det;
    stage_fit_at(&q, u, 1, &fit, &det);
    return fit.G;
}

int pfvi_stage_coefficients(int s, double u, double* out){
    struct pfvi_lobatto q;
    if (!pfvi_lobatto_compute(s, &q)){
        return 0;
    }
    struct pfvi_stage_fit fit;
    double det;
    stage_fit_at(&q, u, 1, &fit, &det);
    const double* rows[6] = {fit.b, fit.bbar, fit.B, fit.Bbar, fit.beta_m, fit.beta_d};
    out[0] = fit.G;
    out[1] = det/q.det_classical;
    for (int r=0; r<6; r++){
        for (int k=0; k<s; k++){
            out[2 + r*s + k] = rows[r][k];
        }
    }
    return 1;
}

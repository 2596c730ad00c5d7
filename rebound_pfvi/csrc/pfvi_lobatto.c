/**
 * pfvi_lobatto.c: the quadrature of the s-point discrete Lagrangian (K&V
 * section 3, "maximal algebraic order"; "Increasing the algebraic order"):
 * Gauss-Lobatto nodes and weights on [0, 1] and the differentiation matrix
 * of the polynomial through the nodes. Nothing here knows of fitting.
 */
#include <float.h>
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

// The grid every coefficient of the classical form lies on: multiples of
// 2^-50, so that sums and differences of coefficients below 8 in size (the
// identities of struct pfvi_lobatto) are exact in doubles. Rounding the
// nodes c and the matrix nu to it perturbs them by at most 4.4e-16: a
// symplectic symmetric method just as close to the rule's, far below any
// truncation error pfvi's epsilon floors allow.
static long double on_grid(long double value){
    const long double quantum = ldexpl(1.L, -50);
    return roundl(value/quantum)*quantum;
}

// The classical step's Runge-Kutta-Nystrom form (pfvi.h, struct
// pfvi_lobatto). In long double: a_ij = int_0^c_i l_j by Gauss-Legendre
// quadrature (exact for l_j's degree s - 1), the IIIB matrix ahat_jk =
// w_k (1 - a_kj/w_j), abar = a ahat. Then on the grid: c (c_s-1-i = 1 - c_i),
// and nu = abar/w, one index pair of each set {(i,j), (j,i), (s-1-i,s-1-j),
// (s-1-j,s-1-i)} from the quadrature and the others from the identities.
static void nystrom_form(int s, const long double* x, struct pfvi_lobatto* rule){
    enum { GAUSS = PFVI_STAGES_MAX/2 + 1 };
    long double xi[GAUSS], weight[GAUSS];
    for (int g=0; g<GAUSS; g++){
        long double root = cosl(M_PI*(g + 0.75L)/(GAUSS + 0.5L)), p, dp;
        for (int it=0; it<100; it++){
            legendre(GAUSS, root, &p, &dp);
            const long double dx = p/dp;
            root -= dx;
            if (fabsl(dx) <= 1e-19L) break;
        }
        legendre(GAUSS, root, &p, &dp);
        xi[g] = root;
        weight[g] = 2.L/((1.L - root*root)*dp*dp);
    }
    const int n = s - 1;
    long double c[PFVI_STAGES_MAX], w[PFVI_STAGES_MAX];
    long double a[PFVI_STAGES_MAX][PFVI_STAGES_MAX], ahat[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    for (int j=0; j<=n; j++){
        long double p, dp;
        legendre(n, x[j], &p, &dp);
        c[j] = 0.5L*(1.L + x[j]);
        w[j] = 1.L/(n*(n + 1)*p*p);
    }
    for (int i=0; i<s; i++){
        for (int j=0; j<s; j++){
            long double integral = 0.L;
            for (int g=0; g<GAUSS; g++){
                const long double t = 0.5L*c[i]*(1.L + xi[g]);
                long double l = 1.L;
                for (int m=0; m<s; m++){
                    if (m != j) l *= (t - c[m])/(c[j] - c[m]);
                }
                integral += weight[g]*l;
            }
            a[i][j] = 0.5L*c[i]*integral;
        }
    }
    for (int i=0; i<s; i++){
        for (int j=0; j<s; j++){
            ahat[i][j] = w[j]*(1.L - a[j][i]/w[i]);
            rule->mu_hat[i][j] = (double)(ahat[i][j]/w[j]);
        }
    }
    for (int i=0; i<=n; i++){
        rule->c_nu[i] = (2*i < n) ? (double)on_grid(c[i]) : (2*i == n) ? 0.5 : 1. - rule->c_nu[n-i];
    }
    for (int i=0; i<s; i++){
        for (int j=0; j<s; j++){
            const int mi = n - i, mj = n - j;
            const int index = i*s + j;
            if (index > j*s + i || index > mi*s + mj || index > mj*s + mi){
                continue;  // not the set's first pair: set from it below
            }
            long double abar = 0.L;
            for (int k=0; k<s; k++){
                abar += a[i][k]*ahat[k][j];
            }
            const double nu = (double)on_grid(abar/w[j]);
            const double* const cn = rule->c_nu;
            rule->nu[i][j] = nu;
            rule->nu[j][i] = nu - cn[i] + cn[j];
            rule->nu[mi][mj] = nu + cn[j] - cn[i];
            rule->nu[mj][mi] = nu;
        }
    }
}

int pfvi_lobatto_compute(int s, struct pfvi_lobatto* rule){
    if (s < PFVI_STAGES_MIN || s > PFVI_STAGES_MAX){
        return 0;
    }
    memset(rule, 0, sizeof(*rule));
    rule->s = s;
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
        rule->c[j] = (double)(0.5L*(1.L + x[j]));
        rule->w[j] = (double)(1.L/(n*(n + 1)*p*p));  // 2/(n(n+1)P^2) on [-1, 1], halved for [0, 1]
        lambda[j] = 1.L;
        for (int m=0; m<=n; m++){
            if (m != j) lambda[j] /= 0.5L*(x[j] - x[m]);
        }
    }
    for (int j=0; j<=n; j++){
        rule->lagrange[j] = (double)lambda[j];
    }
    // Differentiation matrix from the barycentric weights; the diagonal makes
    // every row sum to zero (seed section 6, first condition).
    for (int k=0; k<=n; k++){
        long double diagonal = 0.L;
        for (int j=0; j<=n; j++){
            if (j == k) continue;
            const long double akj = (lambda[j]/lambda[k])/(0.5L*(x[k] - x[j]));
            rule->a[k][j] = (double)akj;
            diagonal -= akj;
        }
        rule->a[k][k] = (double)diagonal;
    }
    nystrom_form(s, x, rule);
    for (int i=0; i<s; i++){
        for (int j=0; j<s; j++){
            rule->nu_t[j][i] = rule->nu[i][j];
        }
    }
    return 1;
}

void pfvi_lagrange_at(const struct pfvi_lobatto* rule, double tau, double* l){
    // l_m(tau) = lagrange[m] (prod_(n < m) (tau - c^n)) (prod_(n > m) (tau - c^n)).
    const int s = rule->s;
    double below[PFVI_STAGES_MAX], above = 1.;
    below[0] = 1.;
    for (int n=1; n<s; n++){
        below[n] = below[n-1]*(tau - rule->c[n-1]);
    }
    for (int m=s-1; m>=0; m--){
        l[m] = rule->lagrange[m]*(below[m]*above);
        above *= tau - rule->c[m];
    }
}

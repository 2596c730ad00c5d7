/**
 * pfvi_lobatto.c: the quadrature of the s-point discrete Lagrangian (K&V
 * section 3, "maximal algebraic order"; "Increasing the algebraic order"):
 * Gauss-Lobatto nodes and weights on [0, 1] and the differentiation matrix
 * of the polynomial through the nodes. Nothing here knows of fitting.
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
    return 1;
}

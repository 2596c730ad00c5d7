/**
 * pfvi_fitting.c: coefficients of the phase-fitted discrete Lagrangian.
 *
 * K&V (section 3) interpolates the stage points and velocities as
 *     q^j    = b^j q_k + bbar^j q_k+1,
 *     qdot^j = (B^j q_k + Bbar^j q_k+1) / h,
 * with coefficients fitted so that the test Lagrangian (the harmonic
 * oscillator at frequency omega) is solved exactly; u = omega h.
 *
 * With two nodes c = (0, 1) and weights (1/2, 1/2), the position-momentum
 * equations p_k = -D1 Ld, p_k+1 = D2 Ld can be solved in closed form. Writing
 * the force as the harmonic part plus a residual, a = -omega^2 q + r, they
 * become (docs/method.md has the derivation):
 *     vt      = v_k / g + (h/2) (tan u / u) r_k
 *     q_k+1   = cos u q_k + (sin u / omega) vt
 *     vr      = -omega sin u q_k + cos u vt
 *     v_k+1   = g [ vr + (h/2) (tan u / u) r_k+1 ]
 * with g = 1 for fitting "phase" (Ld divided by gamma) and g = gamma(u) =
 * u cot u for "phase-literal" (Ld as printed). At u = 0 this is velocity
 * Verlet, bit for bit. The form has no 0/0 at u -> 0 and no pole at u = pi
 * for "phase"; its pole is cos u = 0, where the trapezoidal rule makes
 * d^2 Ld / dq_k dq_k+1 vanish.
 *
 * The s-point scheme (K&V, "Increasing the algebraic order") uses the same
 * coefficients at every Gauss-Lobatto node:
 *     b = sin((1-c)u)/sin u,       bbar = sin(cu)/sin u,
 *     B = -u cos((1-c)u)/sin u,    Bbar = u cos(cu)/sin u,
 * and the combinations the step needs without cancellation,
 *     beta_m = b + bbar - 1 = 2 sin(cu/2) sin((1-c)u/2) / cos(u/2),
 *     beta_d = B + Bbar     = -u sin((2c-1)u/2) / cos(u/2),
 * with the matrix of the linear part of its stage equations (pfvi_stages.c).
 */
#include <math.h>
#include <string.h>
#include "pfvi.h"

// sin(u)/u; the series keeps u = 0 exact and costs nothing for tiny u.
static double sinc(double u, double sin_u){
    if (fabs(u) < 1e-4){
        return 1. - u*u/6.;
    }
    return sin_u/u;
}

enum pfvi_fit_status pfvi_limit_u(double* omega, double h, double u_max, double* u){
    *u = (*omega)*h;
    // Written as !(<=) so that a NaN or Inf frequency estimate is limited too.
    enum pfvi_fit_status status = PFVI_FIT_OK;
    if (!(fabs(*u) <= u_max)){
        *u = copysign(u_max, h);
        *omega = u_max/fabs(h);
        status = PFVI_FIT_LIMITED;
    }
    if (*omega > PFVI_OMEGA_MAX){
        *omega = 0.;
        *u = 0.;
        status = PFVI_FIT_LIMITED;
    }
    return status;
}

enum pfvi_fit_status pfvi_two_point_fit(double omega, double h, double u_max, int literal, struct pfvi_two_point_fit* fit){
    double u;
    const enum pfvi_fit_status status = pfvi_limit_u(&omega, h, u_max, &u);
    if (u == 0.){
        // Classical trapezoidal discrete Lagrangian: exactly velocity Verlet.
        *fit = (struct pfvi_two_point_fit){
            .omega = 0., .keep = 1., .cos_u_m_keep = 0., .h_sinc_u = h, .omega_sin_u = 0.,
            .half_kick = 0.5*h, .gamma = 1.,
        };
        return status;
    }
    const double sin_u = sin(u);
    const double cos_u = cos(u);
    // sin u = 0 matters only away from u = 0 (gamma(0) = 1), i.e. near u = pi.
    if (fabs(cos_u) < PFVI_POLE_GUARD || (literal && fabs(u) > 0.5*M_PI && fabs(sin_u) < PFVI_POLE_GUARD)){
        return PFVI_FIT_POLE;
    }
    const double s = sinc(u, sin_u);
    fit->omega = omega;
    // For cos u > 0 the rotation is applied as an increment to q (round-off
    // relative to the step, as in Verlet), with cos u - 1 = -sin^2 u/(1 + cos u)
    // free of cancellation. For cos u < 0 the increment would exceed q and
    // the plain product is more accurate: measured on the oscillator after
    // 1e4 steps at u = 2.5, 9e-13 against 2.5e-12 (docs/method.md).
    if (cos_u > 0.){
        fit->keep = 1.;
        fit->cos_u_m_keep = -sin_u*sin_u/(1. + cos_u);
    }else{
        fit->keep = cos_u;
        fit->cos_u_m_keep = 0.;
    }
    fit->h_sinc_u = h*s;
    fit->omega_sin_u = omega*sin_u;
    fit->half_kick = 0.5*h*(s/cos_u);
    fit->gamma = literal ? cos_u/s : 1.;  // only phase-literal rescales momenta
    return status;
}

void pfvi_seed_coefficients(double u, double c, double out[4]){
    if (u == 0.){
        // Limits of the seed's formulas: linear interpolation.
        out[0] = 1. - c; out[1] = c; out[2] = -1.; out[3] = 1.;
        return;
    }
    const double cot_u = cos(u)/sin(u);
    out[0] = cos(c*u) - cot_u*sin(c*u);          // b^j
    out[1] = sin(c*u)/sin(u);                    // bbar^j
    out[2] = -u*sin(c*u) - u*cot_u*cos(c*u);     // B^j
    out[3] = u*cos(c*u)/sin(u);                  // Bbar^j
}

double pfvi_gamma(double u){
    const double sin_u = sin(u);
    return cos(u)/sinc(u, sin_u);
}

int pfvi_two_point_coefficients(double omega, double h, double u_max, int literal, double out[6]){
    struct pfvi_two_point_fit fit;
    const enum pfvi_fit_status status = pfvi_two_point_fit(omega, h, u_max, literal, &fit);
    if (status != PFVI_FIT_POLE){
        out[0] = fit.omega; out[1] = fit.keep + fit.cos_u_m_keep; out[2] = fit.h_sinc_u;
        out[3] = fit.omega_sin_u; out[4] = fit.half_kick; out[5] = pfvi_gamma(fit.omega*h);
    }
    return (int)status;
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

// "exact": each interior column j of the differentiation matrix gets the
// least-norm correction that makes the stationarity equation of delta q^j
// hold on the oscillator's exact paths phi = cos, sin of x = u (tau - 1/2):
//     sum_k w_k a~_kj phi'(c^k) = u^2 w_j phi(c^j)
// (with delta q = 0 there, since b and bbar already carry those paths). The
// correction functions keep their values at the nodes, only their slopes
// there change, so Ld keeps the form of K&V's and stays symmetric. The two
// conditions are divided by u^2 and u, so that they stay O(1) as u -> 0,
// where the correction vanishes like u^2.
static void exact_columns(const struct pfvi_lobatto* rule, double u, struct pfvi_stage_fit* fit){
    const int s = rule->s;
    double m1[PFVI_STAGES_MAX], m2[PFVI_STAGES_MAX], sin_x[PFVI_STAGES_MAX], cos_x[PFVI_STAGES_MAX];
    double M11 = 0., M12 = 0., M22 = 0.;
    for (int k=0; k<s; k++){
        const double x = u*(rule->c[k] - 0.5);
        sin_x[k] = sin(x);
        cos_x[k] = cos(x);
        m1[k] = -rule->w[k]*sin_x[k]/u;   // w_k (cos x)'/u^2, per unit tau
        m2[k] = rule->w[k]*cos_x[k];      // w_k (sin x)'/u
        M11 += m1[k]*m1[k]; M12 += m1[k]*m2[k]; M22 += m2[k]*m2[k];
    }
    const double det = M11*M22 - M12*M12;
    for (int j=1; j<s-1; j++){
        double r1 = -rule->w[j]*cos_x[j], r2 = -u*rule->w[j]*sin_x[j];
        for (int k=0; k<s; k++){
            r1 += m1[k]*fit->a[k][j];
            r2 += m2[k]*fit->a[k][j];
        }
        const double l1 = -(M22*r1 - M12*r2)/det;
        const double l2 = -(M11*r2 - M12*r1)/det;
        for (int k=0; k<s; k++){
            fit->a[k][j] += l1*m1[k] + l2*m2[k];
        }
    }
}

// Coefficients, momentum normalisation and factorised matrix at u (u = 0: classical).
void pfvi_stage_fit_at(const struct pfvi_lobatto* rule, double u, int fitting, struct pfvi_stage_fit* fit, double* det){
    const int s = rule->s;
    const int phase = (fitting == PFVI_FITTING_PHASE || fitting == PFVI_FITTING_EXACT);
    memcpy(fit->a, rule->a, sizeof(fit->a));
    fit->classical = (u == 0.);
    if (u == 0.){
        for (int k=0; k<s; k++){
            fit->b[k] = 1. - rule->c[k]; fit->bbar[k] = rule->c[k];
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
            const double c = rule->c[k];
            const double sc = sin(c*u), cc = cos(c*u);
            const double sm = sin((1. - c)*u), cm = cos((1. - c)*u);
            fit->b[k] = sm/sin_u;
            fit->bbar[k] = sc/sin_u;
            fit->B[k] = -u_over_sin_u*cm;
            fit->Bbar[k] = u_over_sin_u*cc;
            fit->beta_m[k] = 2.*sin(0.5*c*u)*sin(0.5*(1. - c)*u)/cos_half;
            fit->beta_d[k] = -u*sin((c - 0.5)*u)/cos_half;
            gamma_sum += rule->w[k]*cos((2.*c - 1.)*u);
        }
        // gamma_s(u): the rule applied to cos(2 omega (t - h/2)) over its
        // exact integral, the factor by which the printed Ld scales the
        // oscillator's exact discrete Lagrangian.
        fit->G = phase ? gamma_sum*u_over_sin_u : 1.;
        if (fitting == PFVI_FITTING_EXACT){
            exact_columns(rule, u, fit);
        }
    }
    // The equations -D1 Ld = G p_k (row 0) and dLd/d(delta q^j) = 0 (rows j),
    // linear in the unknowns (Delta = q_k+1 - q_k, delta q^j) for given stage
    // accelerations.
    //
    // "exact" also moves the harmonic part of the stage accelerations,
    // h^2 a^k = -u^2 d^k + h^2 r^k with d^k = (1 + beta_m^k) d_k + bbar^k Delta
    // + delta q^k, into the matrix, so that the iteration runs on the
    // residual r only (exact in one round on the oscillator, and convergent
    // at any u there).
    fit->u2 = (fitting == PFVI_FITTING_EXACT) ? u*u : 0.;
    const int m = s - 1;
    double row_B[PFVI_STAGES_MAX];  // multipliers of h qdot^k in each equation: w_k B^k, w_k a^k_j
    double row_b[PFVI_STAGES_MAX];  // multipliers of h^2 a^k: w_k b^k, w_j at node j
    memset(fit->lu, 0, sizeof(fit->lu));
    for (int e=0; e<m; e++){
        for (int k=0; k<s; k++){
            row_B[k] = rule->w[k]*(e == 0 ? fit->B[k] : fit->a[k][e]);
            row_b[k] = (e == 0) ? rule->w[k]*fit->b[k] : (k == e ? rule->w[k] : 0.);
        }
        double q0 = 0.;
        for (int k=0; k<s; k++){
            fit->lu[e][0] += row_B[k]*fit->Bbar[k];
            for (int l=1; l<m; l++){
                fit->lu[e][l] += row_B[k]*fit->a[k][l];
            }
            q0 += row_B[k]*fit->beta_d[k];
        }
        if (fit->u2 != 0.){
            for (int k=0; k<s; k++){
                fit->lu[e][0] -= fit->u2*row_b[k]*fit->bbar[k];
                q0 -= fit->u2*row_b[k]*(1. + fit->beta_m[k]);
            }
            for (int l=1; l<m; l++){
                fit->lu[e][l] -= fit->u2*row_b[l];
            }
        }
        fit->q0_row[e] = q0;
    }
    stage_matrix_factor(m, fit, det);
    // solve = L^-1 P, P the weights of the force at stage k in each
    // equation: w_k b^k in row 0 (the momentum), w_j at node j in row j.
    memset(fit->solve, 0, sizeof(fit->solve));
    memset(fit->start_momentum, 0, sizeof(fit->start_momentum));
    memset(fit->start_offset, 0, sizeof(fit->start_offset));
    if (*det != 0.){
        fit->start_momentum[0] = 1.;
        pfvi_stage_solve(fit, m, fit->start_momentum);
        for (int e=0; e<m; e++){
            fit->start_offset[e] = fit->q0_row[e];
        }
        pfvi_stage_solve(fit, m, fit->start_offset);
        for (int k=0; k<s; k++){
            double column[PFVI_STAGES_MAX-1];
            for (int e=0; e<m; e++){
                column[e] = (e == 0) ? rule->w[k]*fit->b[k] : (e == k ? rule->w[k] : 0.);
            }
            pfvi_stage_solve(fit, m, column);
            for (int e=0; e<m; e++){
                fit->solve[e][k] = column[e];
            }
        }
    }
}

// The factorisation swapped whole rows (multipliers included, as LAPACK's
// getrf), so every interchange is applied to b before the forward solve.
void pfvi_stage_solve(const struct pfvi_stage_fit* fit, int m, double* b){
    for (int k=0; k<m; k++){
        const int p = fit->pivot[k];
        if (p != k){
            const double tmp = b[k]; b[k] = b[p]; b[p] = tmp;
        }
    }
    for (int k=0; k<m; k++){
        for (int i=k+1; i<m; i++){
            b[i] -= fit->lu[i][k]*b[k];
        }
    }
    for (int k=m-1; k>=0; k--){
        double sum = b[k];
        for (int j=k+1; j<m; j++){
            sum -= fit->lu[k][j]*b[j];
        }
        b[k] = sum/fit->lu[k][k];
    }
}

// The rule and its classical fit depend on s alone. Made in long double
// they cost about 120k instructions, which the first step of every new
// simulation paid (a tenth of a short run's time); so each s is made once
// per process and copied after, the same bits. A thread that finds an entry
// not yet ready makes its own copy and publishes it only if no other thread
// has begun to (GCC's atomics: the core is C99).
enum { RULE_EMPTY, RULE_MAKING, RULE_READY };
static struct {
    struct pfvi_lobatto rule;
    struct pfvi_stage_fit classical;
} rule_made[PFVI_STAGES_MAX + 1];
static int rule_made_state[PFVI_STAGES_MAX + 1];

static int stage_rule_make(int s, struct pfvi_lobatto* rule, struct pfvi_stage_fit* classical){
    if (!pfvi_lobatto_compute(s, rule)){
        return 0;
    }
    pfvi_stage_fit_at(rule, 0., PFVI_FITTING_NONE, classical, &rule->det_classical);
    classical->omega = 0.;
    return 1;
}

int pfvi_stage_rule(int s, struct pfvi_lobatto* rule, struct pfvi_stage_fit* classical){
    if (s < PFVI_STAGES_MIN || s > PFVI_STAGES_MAX){
        return 0;
    }
    if (__atomic_load_n(&rule_made_state[s], __ATOMIC_ACQUIRE) != RULE_READY){
        struct pfvi_stage_fit fit;
        if (!stage_rule_make(s, rule, &fit)){
            return 0;
        }
        if (classical){
            *classical = fit;
        }
        int expected = RULE_EMPTY;
        if (__atomic_compare_exchange_n(&rule_made_state[s], &expected, RULE_MAKING, 0, __ATOMIC_ACQ_REL,
                    __ATOMIC_ACQUIRE)){
            rule_made[s].rule = *rule;
            rule_made[s].classical = fit;
            __atomic_store_n(&rule_made_state[s], RULE_READY, __ATOMIC_RELEASE);
        }
        return 1;
    }
    *rule = rule_made[s].rule;
    if (classical){
        *classical = rule_made[s].classical;
    }
    return 1;
}

enum pfvi_fit_status pfvi_stage_fit(const struct pfvi_lobatto* rule, double omega, double h,
        double u_max, int fitting, struct pfvi_stage_fit* fit){
    double u;
    const enum pfvi_fit_status status = pfvi_limit_u(&omega, h, u_max, &u);
    double det;
    pfvi_stage_fit_at(rule, u, fitting, fit, &det);
    fit->omega = (u == 0.) ? 0. : omega;
    // Where the matrix is (nearly) singular q_k+1 is not determined by
    // (q_k, p_k); where G vanishes "phase" divides momenta by zero.
    if (!(fabs(det) >= PFVI_POLE_GUARD*fabs(rule->det_classical)) || !(fabs(fit->G) >= PFVI_POLE_GUARD)){
        return PFVI_FIT_POLE;
    }
    return status;
}

int pfvi_stage_coefficients(int s, double u, double* out){
    struct pfvi_lobatto rule;
    if (!pfvi_stage_rule(s, &rule, NULL)){
        return 0;
    }
    struct pfvi_stage_fit fit;
    double det;
    pfvi_stage_fit_at(&rule, u, PFVI_FITTING_PHASE, &fit, &det);
    const double* rows[6] = {fit.b, fit.bbar, fit.B, fit.Bbar, fit.beta_m, fit.beta_d};
    out[0] = fit.G;
    out[1] = det/rule.det_classical;
    for (int r=0; r<6; r++){
        for (int k=0; k<s; k++){
            out[2 + r*s + k] = rows[r][k];
        }
    }
    return 1;
}

int pfvi_stage_differentiation(int s, double u, int fitting, double* out){
    struct pfvi_lobatto rule;
    if (!pfvi_stage_rule(s, &rule, NULL)){
        return 0;
    }
    struct pfvi_stage_fit fit;
    double det;
    pfvi_stage_fit_at(&rule, u, fitting, &fit, &det);
    for (int k=0; k<s; k++){
        for (int j=0; j<s; j++){
            out[k*s + j] = fit.a[k][j];
        }
    }
    return 1;
}

int pfvi_lobatto_table(int s, double* c, double* w, double* a){
    struct pfvi_lobatto rule;
    if (!pfvi_lobatto_compute(s, &rule)){
        return 0;
    }
    for (int k=0; k<s; k++){
        c[k] = rule.c[k];
        w[k] = rule.w[k];
        for (int j=0; j<s; j++){
            a[k*s + j] = rule.a[k][j];
        }
    }
    return 1;
}

int pfvi_nystrom_table(int s, double* c_nu, double* nu, double* mu_hat){
    struct pfvi_lobatto rule;
    if (!pfvi_lobatto_compute(s, &rule)){
        return 0;
    }
    for (int i=0; i<s; i++){
        c_nu[i] = rule.c_nu[i];
        for (int j=0; j<s; j++){
            nu[i*s + j] = rule.nu[i][j];
            mu_hat[i*s + j] = rule.mu_hat[i][j];
        }
    }
    return 1;
}

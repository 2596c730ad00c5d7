/**
 * pfvi_fitting.c: coefficients of the phase-fitted discrete Lagrangian.
 *
 * The seed (section 3) interpolates the stage points and velocities as
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
 */
#include <math.h>
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

enum pfvi_fit_status pfvi_two_point_fit(double omega, double h, double u_max, int literal, struct pfvi_two_point* fit){
    double u;
    const enum pfvi_fit_status status = pfvi_limit_u(&omega, h, u_max, &u);
    if (u == 0.){
        // Classical trapezoidal discrete Lagrangian: exactly velocity Verlet.
        *fit = (struct pfvi_two_point){
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
    struct pfvi_two_point fit;
    const enum pfvi_fit_status status = pfvi_two_point_fit(omega, h, u_max, literal, &fit);
    if (status != PFVI_FIT_POLE){
        out[0] = fit.omega; out[1] = fit.keep + fit.cos_u_m_keep; out[2] = fit.h_sinc_u;
        out[3] = fit.omega_sin_u; out[4] = fit.half_kick; out[5] = pfvi_gamma(fit.omega*h);
    }
    return (int)status;
}

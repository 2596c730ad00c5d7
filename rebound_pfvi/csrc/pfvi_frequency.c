/**
 * pfvi_frequency.c: the local frequency of the seed's section 4, and the
 * scaled arithmetic of the osculating circle shared with pfvi_control.c.
 *
 * The osculating circle at a point of the trajectory has radius
 * R = |v|^3 / |v x a|; a point moving along it at speed |v| turns at the
 * angular rate omega = |v| / R = |v x a| / |v|^2 (seed eq. "equ_freq").
 *
 * |v|^2 overflows above |v| ~ 1.3e154 and underflows below ~ 1.5e-154 (and
 * |v x a| likewise), where the plain formulas give NaN, Inf or 0 for a
 * perfectly regular orbit. There the quantities are computed from v and a
 * scaled by powers of two (exact) to unit size; elsewhere the plain formulas
 * are kept, bit for bit.
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include "pfvi.h"

// x scaled by a power of two so that its largest component lies in [1, 2);
// returns the exponent e with x = 2^e xh, or INT_MIN for x = 0.
static int pfvi_scale_unit(const double x[3], double xh[3]){
    const double m = fmax(fabs(x[0]), fmax(fabs(x[1]), fabs(x[2])));
    if (m == 0.){
        xh[0] = xh[1] = xh[2] = 0.;
        return INT_MIN;
    }
    const int e = ilogb(m);
    for (int c=0; c<3; c++){
        xh[c] = scalbn(x[c], -e);
    }
    return e;
}

int pfvi_curvature_scaled(const double v[3], const double a[3], struct pfvi_curvature* k){
    double vh[3], ah[3];
    const int ev = pfvi_scale_unit(v, vh);
    const int ea = pfvi_scale_unit(a, ah);
    k->omega = 0.;
    k->R = INFINITY;
    if (ev == INT_MIN || ea == INT_MIN){
        return 0;  // at rest, or no acceleration: no circle, omega = 0
    }
    const double w[3] = {vh[1]*ah[2] - vh[2]*ah[1], vh[2]*ah[0] - vh[0]*ah[2], vh[0]*ah[1] - vh[1]*ah[0]};
    const double w2 = w[0]*w[0] + w[1]*w[1] + w[2]*w[2];
    if (!(w2 > 0.)){
        return 0;  // a straight line
    }
    const double v2 = vh[0]*vh[0] + vh[1]*vh[1] + vh[2]*vh[2];
    const double w_norm = sqrt(w2), v_norm = sqrt(v2);
    // omega = |v x a|/|v|^2 and R = |v|^3/|v x a| with the powers of two put back.
    k->omega = scalbn(w_norm/v2, ea - ev);
    k->R = scalbn(v2*v_norm/w_norm, ev - ea + ev);
    // (v x a) x v points from x to the centre; |w x vh| = |w| |vh|.
    const double n[3] = {w[1]*vh[2] - w[2]*vh[1], w[2]*vh[0] - w[0]*vh[2], w[0]*vh[1] - w[1]*vh[0]};
    const double n_norm = w_norm*v_norm;
    for (int c=0; c<3; c++){
        k->normal[c] = n[c]/n_norm;
        k->binormal[c] = w[c]/w_norm;
    }
    return 1;
}

double pfvi_curvature_frequency(const double v[3], const double a[3]){
    const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
    const double cx = v[1]*a[2] - v[2]*a[1];
    const double cy = v[2]*a[0] - v[0]*a[2];
    const double cz = v[0]*a[1] - v[1]*a[0];
    const double c2 = cx*cx + cy*cy + cz*cz;
    if (v2 >= DBL_MIN && v2 <= DBL_MAX && c2 >= DBL_MIN && c2 <= DBL_MAX){
        return sqrt(c2) / v2;
    }
    // Out of the squares' range, at rest, or on a straight line (0).
    struct pfvi_curvature k;
    pfvi_curvature_scaled(v, a, &k);
    return k.omega;
}

double pfvi_step_frequency(const struct pfvi_state* s, const struct reb_particle* p, const double a[3]){
    if (s->fitting == PFVI_FITTING_NONE){
        return 0.;
    }
    if (s->frequency == PFVI_FREQUENCY_FIXED){
        return s->omega;
    }
    const double v[3] = {p->vx, p->vy, p->vz};
    return pfvi_curvature_frequency(v, a);
}

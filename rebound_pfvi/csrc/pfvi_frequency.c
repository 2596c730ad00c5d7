/**
 * pfvi_frequency.c: the local frequency of the seed's section 4.
 *
 * The osculating circle at a point of the trajectory has radius
 * R = |v|^3 / |v x a|; a point moving along it at speed |v| turns at the
 * angular rate omega = |v| / R = |v x a| / |v|^2 (seed eq. "equ_freq").
 */
#include <math.h>
#include "pfvi.h"

double pfvi_curvature_frequency(const double v[3], const double a[3]){
    const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
    // At rest (or with |v|^2 below the smallest normal) the curvature is
    // undefined: fall back to the classical, unfitted scheme.
    if (!(v2 > 0.)){
        return 0.;
    }
    const double cx = v[1]*a[2] - v[2]*a[1];
    const double cy = v[2]*a[0] - v[0]*a[2];
    const double cz = v[0]*a[1] - v[1]*a[0];
    // May be +Inf (or NaN on overflow of the squares); the caller limits
    // u = omega*h to u_max, which catches both.
    return sqrt(cx*cx + cy*cy + cz*cz) / v2;
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

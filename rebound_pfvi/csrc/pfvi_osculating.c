/**
 * pfvi_osculating.c: the geometry of K&V's "Frequency Evaluation and Error
 * Control": the osculating circle of a particle's path, its angular rate
 * (the curvature frequency), and the bound the step control takes from the
 * circles at a step's two ends. Nothing here knows of REBOUND's simulation.
 *
 * The osculating circle at a point of the path has radius R = |v|^3/|v x a|
 * and centre O = x + |v|^2 (v x a) x v / |v x a|^2; a point moving along it
 * at speed |v| turns at omega = |v|/R = |v x a|/|v|^2 (K&V eq. "equ_freq").
 *
 * K&V bound a step's position error by | |R1 - R2| - |O1 - O2| |: if the
 * curvature changes monotonically the two circles are nested, the centre
 * moves along the evolute by less than the radius changes, and the estimate
 * measures how far the path is from the circle the fitted interpolation
 * follows. It is used relative to min(R1, R2), and is symmetric in the two
 * ends and unchanged when velocities are reversed.
 *
 * K&V's paths are planar. On a space curve the centre also moves out of the
 * circle's plane, at R tau per unit length (tau the torsion: dO/ds =
 * R' N + R tau B), a first-order term that is geometry, not integration
 * error; near a straight stretch perturbed out of its plane (a comet passing
 * Jupiter) it made the estimate first order in h and the steps collapse
 * (1e-7 yr at epsilon 1e-9). So the centre's motion is measured in the plane
 * normal to the mean binormal of the two ends, which removes that term to
 * third order and leaves planar motion untouched bit for bit.
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

// The circle where the squares of v or v x a leave the doubles' range.
static void pfvi_osculating_circle_scaled(const double v[3], const double a[3], struct pfvi_osculating* c){
    struct pfvi_curvature k;
    c->defined = 0;
    c->omega = 0.;
    c->R = INFINITY;
    if (!pfvi_curvature_scaled(v, a, &k)){
        return;
    }
    c->omega = k.omega;
    for (int i=0; i<3; i++){
        c->offset[i] = k.R*k.normal[i];
        c->binormal[i] = k.binormal[i];
    }
    if (isfinite(k.R) && k.omega > 0. && isfinite(k.omega)
            && isfinite(c->offset[0]) && isfinite(c->offset[1]) && isfinite(c->offset[2])){
        c->R = k.R;
        c->defined = 1;
    }
}

void pfvi_osculating_circle(const double v[3], const double a[3], struct pfvi_osculating* c){
    const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
    const double w[3] = {v[1]*a[2] - v[2]*a[1], v[2]*a[0] - v[0]*a[2], v[0]*a[1] - v[1]*a[0]};
    const double w2 = w[0]*w[0] + w[1]*w[1] + w[2]*w[2];
    c->defined = 0;
    c->omega = 0.;
    c->R = INFINITY;
    if (!(v2 > 0. && w2 > 0. && v2 <= DBL_MAX && w2 <= DBL_MAX)){
        // At rest or on a straight line (no circle, omega = 0), or the
        // squares left the doubles' range.
        pfvi_osculating_circle_scaled(v, a, c);
        return;
    }
    const double R = v2*sqrt(v2)/sqrt(w2);
    // (v x a) x v points from x to the centre.
    const double n[3] = {w[1]*v[2] - w[2]*v[1], w[2]*v[0] - w[0]*v[2], w[0]*v[1] - w[1]*v[0]};
    const double scale = v2/w2;
    c->offset[0] = scale*n[0];
    c->offset[1] = scale*n[1];
    c->offset[2] = scale*n[2];
    c->omega = sqrt(w2)/v2;
    const double w_norm = sqrt(w2);
    c->binormal[0] = w[0]/w_norm;
    c->binormal[1] = w[1]/w_norm;
    c->binormal[2] = w[2]/w_norm;
    if (isfinite(R) && isfinite(c->omega) && isfinite(c->offset[0]) && isfinite(c->offset[1])
            && isfinite(c->offset[2]) && v2 >= DBL_MIN && w2 >= DBL_MIN && c->omega > 0.){
        c->R = R;
        c->defined = 1;
        return;
    }
    pfvi_osculating_circle_scaled(v, a, c);
}

// Whether the circles at the two ends bound anything. Across an inflection
// (curvature through zero: common in N-body paths, never on a Kepler orbit)
// the binormal flips and the circles lie on opposite sides of the path; the
// estimate is then 2 min(R)/min(R) = 2 however short the step (Burrau's
// problem refused every step at an inflection), so it says nothing there.
int pfvi_osculating_comparable(const struct pfvi_osculating* c0, const struct pfvi_osculating* c1){
    if (!c0->defined || !c1->defined){
        return 0;
    }
    return c0->binormal[0]*c1->binormal[0] + c0->binormal[1]*c1->binormal[1]
        + c0->binormal[2]*c1->binormal[2] >= 0.;
}

double pfvi_osculating_error(const double x0[3], const struct pfvi_osculating* c0,
        const double x1[3], const struct pfvi_osculating* c1, double* noise_out){
    *noise_out = 0.;
    if (!c0->defined || !c1->defined){
        return 0.;
    }
    // O1 - O0 as the step's displacement plus the change of the offsets, so
    // that the positions' size enters only through one rounding.
    double d[3] = {
        (x1[0] - x0[0]) + (c1->offset[0] - c0->offset[0]),
        (x1[1] - x0[1]) + (c1->offset[1] - c0->offset[1]),
        (x1[2] - x0[2]) + (c1->offset[2] - c0->offset[2])};
    // Drop the out-of-plane (torsion) part. (The binormals are within 90
    // degrees here, so their mean is defined; the test is kept as a guard.)
    const double b[3] = {c0->binormal[0] + c1->binormal[0], c0->binormal[1] + c1->binormal[1],
        c0->binormal[2] + c1->binormal[2]};
    const double b2 = b[0]*b[0] + b[1]*b[1] + b[2]*b[2];
    if (b2 > 1.){
        const double along = (d[0]*b[0] + d[1]*b[1] + d[2]*b[2])/b2;
        d[0] -= along*b[0];
        d[1] -= along*b[1];
        d[2] -= along*b[2];
    }
    const double moved = sqrt(d[0]*d[0] + d[1]*d[1] + d[2]*d[2]);
    const double r_min = fmin(c0->R, c1->R), r_max = fmax(c0->R, c1->R);
    const double estimate = fabs((r_max - r_min) - moved)/r_min;
    // Both terms are first order in h and cancel to third: below a few
    // roundings of |x| and R the difference is noise, not error.
    const double size = fmax(fmax(fabs(x0[0]), fabs(x1[0])), fmax(fmax(fabs(x0[1]), fabs(x1[1])),
                fmax(fabs(x0[2]), fabs(x1[2]))));
    const double noise = 8.*DBL_EPSILON*(size + r_max)/r_min;
    *noise_out = noise;
    return (estimate > noise) ? estimate - noise : 0.;
}

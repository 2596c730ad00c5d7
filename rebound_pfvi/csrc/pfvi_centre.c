/**
 * pfvi_centre.c: the centre and the frequency of each particle's harmonic
 * model (docs/fitting.md).
 *
 * K&V fit the interpolation to the oscillator q'' = -omega^2 q about the
 * coordinate origin, with omega from the curvature of the path in the
 * simulation frame: the step then depends on the inertial frame, and a star
 * in a centre-of-mass frame, whose force ignores its own position, is
 * modelled as bound to the origin. Here the model is the oscillator
 *     d'' = -omega^2 d,   d = q - c(t),   c(t0 + tau h) = c0 + tau h vc,
 * about a centre moving with constant acceleration over the step, c(t0 + t)
 * = c0 + t vc + t^2 ac/2. With L(d) = |d'|^2/2 - V(c + d) - ac.d (a frame
 * in uniform motion changes L by a total derivative; its acceleration adds
 * the force -ac) the discrete Lagrangian of the schemes is applied to d,
 * p - c' and the force a - ac unchanged; the centre and omega are
 * parameters of the step, taken at its start.
 *
 * The centre "partner" refers each particle to the barycentre of itself
 * and its partner: the body j of largest G (m_i + m_j) / r_ij^3, the
 * tightest pair it is in (the Hill criterion: a moon's partner is its
 * planet, not the star that pulls it harder), and its frequency to the pair's
 * relative motion under the partner's attraction alone. A planet whose
 * moon makes the tightest pair circles the pair's barycentre at the moon's
 * frequency; fitted to its whole acceleration (the star's pull, almost)
 * about that nearby centre, it would get omega ~ 1/sqrt(|d|) and lose the
 * star (measured: benchmarks/fitting.py, part C, 0.15 of the moon's
 * distance after one orbit of the planet). In a two-body problem this
 * barycentre moves uniformly and both bodies circle it at the same
 * frequency, so a circular pair is exact for both; translating and boosting
 * the whole system moves every centre with it.
 */
#include <math.h>
#include <stdlib.h>
#include "pfvi.h"

// Largest |x_k|, for scaling a vector before squaring it.
static double vector_scale(const double x[3]){
    return fmax(fabs(x[0]), fmax(fabs(x[1]), fabs(x[2])));
}

void pfvi_centres(const struct reb_particle* p, const struct pfvi_end_state* start, size_t N,
        size_t N_active, double G, int centre, const struct pfvi_partner* partners, struct pfvi_centre* c){
    const size_t n_attracting = (N_active < N) ? N_active : N;
    // The barycentre of the attracting bodies, for the centre "barycentre".
    double M = 0., X[3] = {0., 0., 0.}, V[3] = {0., 0., 0.};
    if (centre == PFVI_CENTRE_BARYCENTRE && G > 0.){
        for (size_t j=0; j<n_attracting; j++){
            M += p[j].m;
        }
        // Tiny masses: from mass fractions, as the pairs' barycentres
        // (m x underflows below PFVI_MASS_TINY; the products otherwise, so
        // that every trajectory stays as it was).
        const int tiny = !(M > PFVI_MASS_TINY);
        for (size_t j=0; j<n_attracting; j++){
            const double m = tiny ? p[j].m/M : p[j].m;
            X[0] += m*p[j].x; X[1] += m*p[j].y; X[2] += m*p[j].z;
            V[0] += m*p[j].vx; V[1] += m*p[j].vy; V[2] += m*p[j].vz;
        }
        if (tiny){
            M = (M > 0.) ? 1. : M;   // X and V are already the barycentre's
        }
    }
    const int barycentre = (centre == PFVI_CENTRE_BARYCENTRE && M > 0. && isfinite(M));
    for (size_t i=0; i<N; i++){
        struct pfvi_centre* const ci = &c[i];
        *ci = (struct pfvi_centre){{0., 0., 0.}, {0., 0., 0.}, {0., 0., 0.}, {0., 0., 0.}, 0., SIZE_MAX};
        ci->partner = partners ? partners[i].j : SIZE_MAX;
        if (ci->partner != SIZE_MAX){
            const struct reb_particle* const q = &p[ci->partner];
            const double dx = q->x - p[i].x, dy = q->y - p[i].y, dz = q->z - p[i].z;
            const double r = sqrt(dx*dx + dy*dy + dz*dz);
            const double pull = G*q->m/(r*r*r);
            ci->a[0] = pull*dx; ci->a[1] = pull*dy; ci->a[2] = pull*dz;
            ci->mu = G*(p[i].m + q->m);
        }
        if (barycentre){
            ci->x[0] = X[0]/M; ci->x[1] = X[1]/M; ci->x[2] = X[2]/M;
            ci->v[0] = V[0]/M; ci->v[1] = V[1]/M; ci->v[2] = V[2]/M;
        }else if (centre == PFVI_CENTRE_PARTNER && ci->partner != SIZE_MAX){
            const struct reb_particle* const q = &p[ci->partner];
            const double m = p[i].m + q->m;
            const double fi = p[i].m/m, fj = q->m/m;
            // The pair's barycentre as an offset from the heavier body: a
            // test particle's centre is its partner's position to the bit.
            const struct reb_particle* const heavy = (fi > 0.5) ? &p[i] : q;
            const struct reb_particle* const light = (fi > 0.5) ? q : &p[i];
            const double f = (fi > 0.5) ? fj : fi;
            ci->x[0] = heavy->x + f*(light->x - heavy->x);
            ci->x[1] = heavy->y + f*(light->y - heavy->y);
            ci->x[2] = heavy->z + f*(light->z - heavy->z);
            ci->v[0] = fi*p[i].vx + fj*q->vx;
            ci->v[1] = fi*p[i].vy + fj*q->vy;
            ci->v[2] = fi*p[i].vz + fj*q->vz;
            // The pair's barycentre falls with the pair: its acceleration
            // (what the rest of the system does to the pair) moves the
            // centre, so that d = q - c sees the partner and the tide only.
            const double* const ai = start[i].a;
            const double* const aj = start[ci->partner].a;
            ci->acc[0] = fi*ai[0] + fj*aj[0];
            ci->acc[1] = fi*ai[1] + fj*aj[1];
            ci->acc[2] = fi*ai[2] + fj*aj[2];
        }
    }
}

double pfvi_radial_frequency(const double d[3], const double a[3]){
    const double s = vector_scale(d);
    if (!(s > 0.) || !isfinite(s)){
        return 0.;
    }
    const double e[3] = {d[0]/s, d[1]/s, d[2]/s};
    const double pull = -(a[0]*e[0] + a[1]*e[1] + a[2]*e[2]);
    if (!(pull > 0.)){
        return (pull != pull) ? NAN : 0.;
    }
    return sqrt(pull/(s*(e[0]*e[0] + e[1]*e[1] + e[2]*e[2])));
}

// The mean motion sqrt(mu / A^3) of the osculating two-body orbit of i about
// its partner (A its semi-major axis); 0 if it is not bound.
static double mean_motion(const struct reb_particle* p, const struct reb_particle* q, double mu){
    const double dx[3] = {p->x - q->x, p->y - q->y, p->z - q->z};
    const double dv[3] = {p->vx - q->vx, p->vy - q->vy, p->vz - q->vz};
    const double r = sqrt(dx[0]*dx[0] + dx[1]*dx[1] + dx[2]*dx[2]);
    const double v2 = dv[0]*dv[0] + dv[1]*dv[1] + dv[2]*dv[2];
    const double inverse_a = 2./r - v2/mu;
    if (!(inverse_a > 0.) || !(mu > 0.)){
        return (inverse_a != inverse_a) ? NAN : 0.;
    }
    return sqrt(mu*inverse_a)*inverse_a;
}

double pfvi_frequency(const struct pfvi_options* o, const struct reb_particle* p,
        const struct reb_particle* partner, const struct pfvi_centre* c, const double a[3]){
    if (o->fitting == PFVI_FITTING_NONE){
        return 0.;
    }
    // About a partner, the pair's own motion: a planet whose partner is its
    // moon circles their barycentre at the moon's frequency while the star's
    // pull (its whole acceleration, almost) is the residual.
    if (o->centre == PFVI_CENTRE_PARTNER && c->partner != SIZE_MAX){
        a = c->a;
    }
    switch (o->frequency){
        case PFVI_FREQUENCY_FIXED:
            return o->omega;
        case PFVI_FREQUENCY_RADIAL:
        {
            const double d[3] = {p->x - c->x[0], p->y - c->x[1], p->z - c->x[2]};
            return pfvi_radial_frequency(d, a);
        }
        case PFVI_FREQUENCY_MEAN_MOTION:
            return partner ? mean_motion(p, partner, c->mu) : 0.;
        default:
        {
            const double w[3] = {p->vx - c->v[0], p->vy - c->v[1], p->vz - c->v[2]};
            return pfvi_curvature_frequency(w, a);
        }
    }
}

/**
 * pfvi_timescales.c: the time scales that limit a step, as one step density
 * sigma(y), a function of the state alone (positions, velocities, masses,
 * accelerations), so that the symmetric control of pfvi_control.c can track
 * it time-symmetrically; and the resolution of a step's own stages, the a
 * posteriori check of that density (docs/adaptive.md).
 *
 * The density is the smooth maximum sigma = (sum_k t_k^K)^(1/K) of two kinds
 * of terms:
 *  - Kepler terms, one per body: the frequency (mu/r^3)^(1/2) of the body's
 *    osculating orbit about the subsystem it orbits, times (1 - e^2)^(-gamma_s)
 *    (e that orbit's eccentricity; the factor evens out the error per orbit
 *    over eccentricities, measured). The subsystem is the body's partner
 *    (the attracting body of largest (m_i + m_j)/r^3, its tightest pair) and
 *    whatever that partner is bound to more tightly than the body is to it:
 *    a circumbinary planet orbits the binary, a moon its planet, a Jupiter
 *    family comet the Sun (and Jupiter, beyond Jupiter's distance).
 *  - Encounter terms, one per pair of bodies (and ghost image) that is not
 *    bound: a flyby's time scale is the crossing time r/v, which no orbital
 *    frequency shows. The term nu_ff (q - 2^(1/2)) (1 + c cos^2 theta),
 *    q = nu_cr/nu_ff with nu_ff = (mu/r^3)^(1/2) and nu_cr = v/r, theta the
 *    angle between r and v, is zero for every bound pair (q <= 2^(1/2)) and
 *    nu_cr (1 + c cos^2 theta) for a fast one: v/b at closest approach b,
 *    (1 + c) v/r approaching and receding. So it changes by at most
 *    1/(1 + c) of itself per unit time, and the track can follow it (a
 *    term that changes faster than itself is not trackable: nu_cr alone
 *    left steps twice too long on leaving Jupiter, and one weighted down by
 *    the deflection, nu_cr (mu/(v^2 r))^(1/(2s - 2)), left a passage at
 *    2.5 AU under-resolved; both measured).
 * Both use the softened distance, and where REBOUND sums over ghost boxes
 * every image of a pair is a pair (a partner may be an image). The logarithmic rate d log(sigma)/dt is
 * exact along the motion: each term's from r, v and the relative
 * acceleration.
 *
 * The resolution check measures a body's stage accelerations against the
 * forces acting on it, not only against its net acceleration: where pulls
 * cancel (the centre of a symmetric ring, a body between two equal masses)
 * the net acceleration is round-off of the pulls, and its variation over
 * the stages is round-off too, which against the net acceleration alone
 * read as an unresolved force (issue 36: the six-body ring was retaken
 * without end). So a body whose stages look unresolved is measured again
 * against the largest single pull on it at either end of the step
 * (pfvi_largest_pull2).
 */
#include <math.h>
#include <string.h>
#include "pfvi.h"

// Whether body i attracts others in REBOUND's sum: an active body with mass.
static inline int attracts(const struct reb_particle* p, size_t i, size_t n_attracting){
    return i < n_attracting && p[i].m > 0.;
}

// The positions of bodies j0 .. j0 + 3 as lanes (lanes past n repeat the
// first: finite values, computed and dropped).
struct lanes_block {
    pfvi_lanes x, y, z, vx, vy, vz, m;
};

static inline __attribute__((always_inline)) void block_of(const struct reb_particle* p, size_t j0, size_t n, struct lanes_block* b){
    double v[7][4];
    for (size_t l=0; l<4; l++){
        const struct reb_particle* const q = &p[j0 + ((l < n) ? l : 0)];
        v[0][l] = q->x; v[1][l] = q->y; v[2][l] = q->z;
        v[3][l] = q->vx; v[4][l] = q->vy; v[5][l] = q->vz; v[6][l] = q->m;
    }
    memcpy(&b->x, v[0], sizeof(b->x)); memcpy(&b->y, v[1], sizeof(b->y)); memcpy(&b->z, v[2], sizeof(b->z));
    memcpy(&b->vx, v[3], sizeof(b->vx)); memcpy(&b->vy, v[4], sizeof(b->vy)); memcpy(&b->vz, v[5], sizeof(b->vz));
    memcpy(&b->m, v[6], sizeof(b->m));
}

// The particles j0 .. j0 + 3 (j0 a multiple of 4) from the field's blocks
// where pfvi_partner_search filled them, else gathered (the lanes beyond
// n, which no caller reads, differ between the two).
static inline __attribute__((always_inline)) void block_at(const struct pfvi_field* f, const struct reb_particle* p,
        size_t N, size_t j0, size_t n, struct lanes_block* b){
    if (!f->blocks || N > f->blocks_N){
        block_of(p, j0, n, b);
        return;
    }
    const struct pfvi_lanes_block* const k = &f->blocks[j0/4];
    memcpy(&b->x, k->x, sizeof(b->x)); memcpy(&b->y, k->y, sizeof(b->y)); memcpy(&b->z, k->z, sizeof(b->z));
    memcpy(&b->vx, k->vx, sizeof(b->vx)); memcpy(&b->vy, k->vy, sizeof(b->vy)); memcpy(&b->vz, k->vz, sizeof(b->vz));
    memcpy(&b->m, k->m, sizeof(b->m));
}

// Fills the field's blocks with the particles p (once per scan: O(N)).
static void blocks_fill(const struct pfvi_field* f, const struct reb_particle* p, size_t N){
    if (!f->blocks || N > f->blocks_N){
        return;
    }
    for (size_t j0=0; j0<N; j0+=4){
        struct pfvi_lanes_block* const k = &f->blocks[j0/4];
        for (size_t l=0; l<4; l++){
            const struct reb_particle* const q = &p[(j0 + l < N) ? j0 + l : j0];
            k->x[l] = q->x; k->y[l] = q->y; k->z[l] = q->z;
            k->vx[l] = q->vx; k->vy[l] = q->vy; k->vz[l] = q->vz; k->m[l] = q->m;
        }
    }
}

#define lanes_of(x) ((pfvi_lanes){(x), (x), (x), (x)})

// Without ghost boxes: the pairs' stiffnesses four at a time in vector lanes
// (each lane the scalar expression), then compared in the scalar loop's order.
static inline __attribute__((always_inline)) void partner_search_lanes(const struct reb_particle* p, size_t N, const struct pfvi_field* f,
        size_t n_attracting, struct pfvi_partner* out){
    const struct reb_vec6d* const s = &f->images[0];
    const pfvi_lanes sx = lanes_of(s->x), sy = lanes_of(s->y), sz = lanes_of(s->z), soft = lanes_of(f->softening2);
    for (size_t i=0; i<N; i++){
        const int i_attracts = attracts(p, i, n_attracting);
        const size_t before = (i < n_attracting) ? i : n_attracting;
        const pfvi_lanes xi = lanes_of(p[i].x), yi = lanes_of(p[i].y), zi = lanes_of(p[i].z), mi = lanes_of(p[i].m);
        for (size_t j0=0; j0<before; j0+=4){
            const size_t n = (before - j0 < 4) ? before - j0 : 4;
            struct lanes_block b;
            block_at(f, p, N, j0, n, &b);
            const pfvi_lanes dx = (b.x + sx) - xi, dy = (b.y + sy) - yi, dz = (b.z + sz) - zi;
            const pfvi_lanes r2 = (dx*dx + dy*dy + dz*dz) + soft;
            pfvi_lanes root;
            for (int l=0; l<4; l++){
                root[l] = sqrt(r2[l]);
            }
            const pfvi_lanes stiffness = (mi + b.m)/(r2*root);
            for (size_t l=0; l<n; l++){
                const size_t j = j0 + l;
                const int j_attracts = (p[j].m > 0.);
                if (!(i_attracts || j_attracts)){
                    continue;
                }
                if (j_attracts && stiffness[l] > out[i].stiffness){
                    out[i] = (struct pfvi_partner){j, 0, stiffness[l], 0., 0.};
                }
                if (i_attracts && stiffness[l] > out[j].stiffness){
                    out[j] = (struct pfvi_partner){i, 0, stiffness[l], 0., 0.};
                }
            }
        }
    }
}

PFVI_VECTOR_CLONES
void pfvi_partner_search(const struct reb_particle* p, size_t N, const struct pfvi_field* f,
        struct pfvi_partner* out){
    const size_t n_attracting = (f->N_active < N) ? f->N_active : N;
    for (size_t i=0; i<N; i++){
        out[i] = (struct pfvi_partner){SIZE_MAX, 0, 0., 0., 0.};
    }
    if (!(f->G > 0.)){
        return;
    }
    const size_t n_images = f->n_images;
    if (n_images == 1){
        blocks_fill(f, p, N);
        partner_search_lanes(p, N, f, n_attracting, out);
        return;
    }
    // A pair's stiffness (m_i + m_j)/r^3 is the same for both bodies, so each
    // pair (and image) is measured once, when the outer loop reaches the
    // later body of the two. Each body still meets its candidates in
    // increasing index (and image), and the first of equal stiffnesses wins.
    for (size_t i=0; i<N; i++){
        const int i_attracts = attracts(p, i, n_attracting);
        const size_t before = (i < n_attracting) ? i : n_attracting;
        for (size_t j=0; j<before; j++){
            const int j_attracts = (p[j].m > 0.);
            if (!(i_attracts || j_attracts)){
                continue;
            }
            const double m = p[i].m + p[j].m;
            for (size_t g=0; g<n_images; g++){
                // j's image g relative to i; i's image relative to j is the mirrored one.
                const struct reb_vec6d* const s = &f->images[g];
                const double dx = (p[j].x + s->x) - p[i].x, dy = (p[j].y + s->y) - p[i].y,
                    dz = (p[j].z + s->z) - p[i].z;
                const double r2 = (dx*dx + dy*dy + dz*dz) + f->softening2;
                // m / r^3 compared as (m / r^3)^2 = m^2 / r^6 would
                // overflow sooner; m / (r2 sqrt(r2)) is monotonic in it.
                const double stiffness = m/(r2*sqrt(r2));
                if (j_attracts && stiffness > out[i].stiffness){
                    out[i] = (struct pfvi_partner){j, g, stiffness, 0., 0.};
                }
                if (i_attracts && stiffness > out[j].stiffness){
                    out[j] = (struct pfvi_partner){i, n_images - 1 - g, stiffness, 0., 0.};
                }
            }
        }
    }
}

// A ghost box's shift as (x, y, z, vx, vy, vz).
static inline void shift_of(const struct reb_vec6d* g, double out[6]){
    out[0] = g->x; out[1] = g->y; out[2] = g->z;
    out[3] = g->vx; out[4] = g->vy; out[5] = g->vz;
}

// The acceleration of particle i: that of the state `start` holds, or p's own.
static inline const double* acceleration_of(const struct reb_particle* p, const struct pfvi_end_state* start, size_t i){
    return start ? start[i].a : &p[i].ax;
}

// The orbit of body i about its subsystem (pfvi_timescales.c's header): the
// relative position, velocity and acceleration to the subsystem's
// barycentre and mu = G (m_i + M). Returns 0 without a partner.
struct kepler_orbit {
    double r[3], v[3], a[3];
    double mu;
};

static int subsystem_orbit(const struct reb_particle* p, const struct pfvi_end_state* start, size_t i,
        const struct pfvi_field* f, const struct pfvi_partner* partners, struct kepler_orbit* o){
    const struct pfvi_partner* const first = &partners[i];
    if (first->j == SIZE_MAX){
        return 0;
    }
    // Members and the shifts of their images: the partner, then while the
    // last member's own partner is bound to it more tightly than i is to
    // the first, that partner (not i, not already in).
    size_t member[PFVI_SUBSYSTEM_MAX];
    double shift[PFVI_SUBSYSTEM_MAX][6];
    int n = 1;
    member[0] = first->j;
    shift_of(&f->images[first->image], shift[0]);
    while (n < PFVI_SUBSYSTEM_MAX){
        const struct pfvi_partner* const next = &partners[member[n-1]];
        const size_t k = next->j;
        if (k == SIZE_MAX || k == i || !(next->stiffness > first->stiffness)){
            break;
        }
        int known = 0;
        for (int m=0; m<n; m++){
            known |= (member[m] == k);
        }
        if (known){
            break;
        }
        double s[6];
        shift_of(&f->images[next->image], s);
        for (int c=0; c<6; c++){
            shift[n][c] = shift[n-1][c] + s[c];
        }
        member[n++] = k;
    }
    // The barycentre as an offset from the first member, so that a single
    // partner is its own position to the bit.
    const struct reb_particle* const q = &p[member[0]];
    const double q0[6] = {q->x + shift[0][0], q->y + shift[0][1], q->z + shift[0][2],
        q->vx + shift[0][3], q->vy + shift[0][4], q->vz + shift[0][5]};
    double M = q->m, offset[6] = {0., 0., 0., 0., 0., 0.}, A[3];
    const double* const a0 = acceleration_of(p, start, member[0]);
    for (int c=0; c<3; c++){
        A[c] = q->m*a0[c];
    }
    for (int m=1; m<n; m++){
        const struct reb_particle* const b = &p[member[m]];
        const double xv[6] = {b->x + shift[m][0], b->y + shift[m][1], b->z + shift[m][2],
            b->vx + shift[m][3], b->vy + shift[m][4], b->vz + shift[m][5]};
        const double* const ab = acceleration_of(p, start, member[m]);
        for (int c=0; c<6; c++){
            offset[c] += b->m*(xv[c] - q0[c]);
        }
        for (int c=0; c<3; c++){
            A[c] += b->m*ab[c];
        }
        M += b->m;
    }
    const double* const ai = acceleration_of(p, start, i);
    const double xi[6] = {p[i].x, p[i].y, p[i].z, p[i].vx, p[i].vy, p[i].vz};
    for (int c=0; c<3; c++){
        o->r[c] = xi[c] - (q0[c] + offset[c]/M);
        o->v[c] = xi[c+3] - (q0[c+3] + offset[c+3]/M);
        o->a[c] = ai[c] - A[c]/M;
    }
    o->mu = f->G*(p[i].m + M);
    return 1;
}

// Whether body i's subsystem is its partner alone (the partner's own partner
// is i, or bound to it less tightly than i is).
static int single_partner(const struct pfvi_partner* partners, size_t i){
    const struct pfvi_partner* const first = &partners[i];
    const struct pfvi_partner* const next = &partners[first->j];
    return next->j == SIZE_MAX || next->j == i || !(next->stiffness > first->stiffness);
}

// A Kepler term (0 if it could not reach `negligible`): (mu/r_s^3)^(1/2)
// (1 - e^2)^(-gamma), with |1 - e^2| held within [1 - PFVI_DENSITY_E2_MAX, 1] (bound orbits beyond e = 0.999 and
// unbound ones below e^2 = 2 - PFVI_DENSITY_E2_MAX get the same factor; an
// orbit that is unbound by more gets none, continuously at e^2 = 2), and the
// time derivative of its logarithm, -3/2 (r.v)/r_s^2 + gamma d(e^2)/dt /
// (1 - e^2) with d(e^2)/dt from the acceleration beyond the subsystem's own
// pull (zero for an isolated pair). Returns 0 where the frequency is not a
// finite positive number.
static int kepler_term(const struct kepler_orbit* o, double softening2, double gamma, double factor_max,
        double negligible, double* term, double* dlog){
    const double* const r = o->r;
    const double* const v = o->v;
    const double mu = o->mu;
    const double r2 = r[0]*r[0] + r[1]*r[1] + r[2]*r[2];
    const double rs2 = r2 + softening2;
    const double omega = sqrt(mu/(rs2*sqrt(rs2)));
    if (!(omega > 0.) || !isfinite(omega)){
        return 0;
    }
    // At most omega times the largest factor: negligible if that is.
    if (omega*factor_max < negligible){
        return 0;
    }
    const double rn = sqrt(r2);
    const double rv = r[0]*v[0] + r[1]*v[1] + r[2]*v[2];
    const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
    double factor = 1., dlog_factor = 0.;
    if (gamma > 0. && rn > 0.){
        double pert[3];
        for (int k=0; k<3; k++){
            pert[k] = o->a[k] + mu*r[k]/(r2*rn);   // beyond the subsystem's pull
        }
        const double vp = v[0]*pert[0] + v[1]*pert[1] + v[2]*pert[2];
        const double rp = r[0]*pert[0] + r[1]*pert[1] + r[2]*pert[2];
        double e2 = 0., de2 = 0.;
        for (int k=0; k<3; k++){
            const double ev = ((v2 - mu/rn)*r[k] - rv*v[k])/mu;
            const double de = (2.*vp*r[k] - rp*v[k] - rv*pert[k])/mu;
            e2 += ev*ev;
            de2 += 2.*ev*de;
        }
        const double x = 1. - e2, held = fabs(x);
        const double floor = 1. - PFVI_DENSITY_E2_MAX;
        if (held <= floor){
            factor = factor_max;   // (pow(floor, -gamma))
        }else if (held < 1.){
            factor = pow(held, -gamma);
            dlog_factor = gamma*de2/x;
        }
    }
    *term = omega*factor;
    *dlog = -1.5*rv/rs2 + dlog_factor;
    return isfinite(*term) && isfinite(*dlog);
}

// The running smooth maximum (sum_k t_k^K)^(1/K), kept as the largest term
// and the sum of (t_k/largest)^K, so that nothing overflows, with the
// weighted mean of the terms' logarithmic rates.
struct density_sum {
    double largest;
    double sum;
    double weighted;
};

typedef char pfvi_density_norm_is_8[(PFVI_DENSITY_NORM == 8) ? 1 : -1];
typedef char pfvi_encounter_fast_power_is_4[(PFVI_ENCOUNTER_FAST_POWER == 4) ? 1 : -1];

// x^K by squaring.
static inline double power_K(double x){
    const double x2 = x*x, x4 = x2*x2;
    return x4*x4;
}

// Adds `count` equal terms.
static void density_add(struct density_sum* d, double term, double dlog, double count){
    if (term > d->largest){
        const double w = power_K(d->largest/term);
        d->sum = d->sum*w + count;
        d->weighted = d->weighted*w + count*dlog;
        d->largest = term;
    }else{
        const double w = count*power_K(term/d->largest);
        d->sum += w;
        d->weighted += w*dlog;
    }
}

// Each body's partner's pull m_j/r^2 (softened, G left out) and its d log/dt,
// for the encounter terms' weights; 0 without a massive partner.
static void partner_pulls(const struct reb_particle* p, size_t N, const struct pfvi_field* f,
        struct pfvi_partner* partners){
    for (size_t b=0; b<N; b++){
        struct pfvi_partner* const q = &partners[b];
        q->pull = 0.;
        q->dlog_pull = 0.;
        if (q->j == SIZE_MAX || !(p[q->j].m > 0.)){
            continue;
        }
        const struct reb_vec6d* const sh = &f->images[q->image];
        const double e[3] = {(p[q->j].x + sh->x) - p[b].x, (p[q->j].y + sh->y) - p[b].y, (p[q->j].z + sh->z) - p[b].z};
        const double u[3] = {(p[q->j].vx + sh->vx) - p[b].vx, (p[q->j].vy + sh->vy) - p[b].vy,
            (p[q->j].vz + sh->vz) - p[b].vz};
        const double r2 = (e[0]*e[0] + e[1]*e[1] + e[2]*e[2]) + f->softening2;
        q->pull = p[q->j].m/r2;
        q->dlog_pull = -2.*(e[0]*u[0] + e[1]*u[1] + e[2]*u[2])/r2;
        if (!(q->pull > 0.) || !isfinite(q->pull) || !isfinite(q->dlog_pull)){
            q->pull = 0.;
            q->dlog_pull = 0.;
        }
    }
}

// How strongly `other` (mass m_other, relative position d and velocity w
// from body b) pulls on b against b's partner: R = (m_other/r^2)/pull (with
// d log R/dt). Infinite where the other body is b's partner (in that image)
// or b has no massive partner.
static double pull_ratio(const struct pfvi_field* f, const struct pfvi_partner* partners, size_t b, size_t other,
        size_t image, double m_other, const double d[3], const double w[3], double* dlog){
    *dlog = 0.;
    const struct pfvi_partner* const q = &partners[b];
    if (!(q->pull > 0.) || (q->j == other && q->image == image)){
        return INFINITY;
    }
    if (!(m_other > 0.)){
        return 0.;
    }
    const double rd2 = (d[0]*d[0] + d[1]*d[1] + d[2]*d[2]) + f->softening2;
    *dlog = -q->dlog_pull - 2.*(d[0]*w[0] + d[1]*w[1] + d[2]*w[2])/rd2;
    return (m_other/rd2)/q->pull;
}

// The pair (i, j's image g) an encounter term belongs to, for its weight.
struct encounter_pair {
    const struct reb_particle* p;
    const struct pfvi_field* f;
    const struct pfvi_partner* partners;
    size_t i, j, g;
    int i_attracts;
    double exponent;    // 1/(2s - 2); 0: unweighted
    int order;          // 2s - 2
};

// Whether the weight x = R/(1 + R) reaches the floor least^order, the
// product least*least*... taken in that order: with 0 <= least <= 1 no
// partial product is below the last, so once one is at or below x the
// whole is too and the product stops there (the same decision).
static inline int weight_reaches(double x, double least, int order){
    const int shrinking = (least >= 0. && least <= 1.);
    double floor = 1.;
    for (int k=0; k<order; k++){
        floor *= least;
        if (shrinking && floor <= x){
            break;
        }
    }
    return !(x < floor);
}

// The weight (R'/(1 + R'))^(1/(2s - 2)) of a pair's encounter term and d
// log(weight)/dt; 1 where the pair is either body's tightest. R' = R + X^p:
// R = R_i + R_j the pair's pull on each body against the body's partner
// (pfvi.h, PFVI_ENCOUNTER_WEIGHTED), X = nu_cr^2/(G (S_i + S_j)) its crossing
// rate against the bodies' partner frequencies (S the partner stiffness
// (m_i + m_j)/r^3), p = PFVI_ENCOUNTER_FAST_POWER. A slow pair (planets about
// a star passing each other, X ~ 0.1) keeps the weight its pull gives; a
// pair that crosses faster than the bodies orbit (a retrograde body passing
// Jupiter, X ~ 2) is weighted 1, as it was before the weighting: the step
// track could not follow a weighted term through a passage shorter than a
// step (issue 40). Returns 0 where the weight is 0.
static int encounter_weight(const struct encounter_pair* q, const double d[3], const double w[3], const double b[3],
        double least, double* weight, double* dlog){
    *weight = 1.;
    *dlog = 0.;
    if (!(q->exponent > 0.)){
        return 1;
    }
    const double dm[3] = {-d[0], -d[1], -d[2]}, wm[3] = {-w[0], -w[1], -w[2]};
    double dlog_i, dlog_j;
    const double R_i = pull_ratio(q->f, q->partners, q->i, q->j, q->g, q->p[q->j].m, d, w, &dlog_i);
    if (!isfinite(R_i)){
        return 1;
    }
    const double R_j = pull_ratio(q->f, q->partners, q->j, q->i, q->f->n_images - 1 - q->g,
        q->i_attracts ? q->p[q->i].m : 0., dm, wm, &dlog_j);
    if (!isfinite(R_j)){
        return 1;
    }
    // The crossing rate against the partner frequencies (each partner's
    // stiffness changes as its pull does, to the power 3/2).
    const struct pfvi_partner* const pi = &q->partners[q->i];
    const struct pfvi_partner* const pj = &q->partners[q->j];
    const double S_i = (pi->pull > 0.) ? pi->stiffness : 0., S_j = (pj->pull > 0.) ? pj->stiffness : 0.;
    const double S = S_i + S_j;
    double Q = 0., dQ = 0.;
    if (S > 0.){
        const double rs2 = (d[0]*d[0] + d[1]*d[1] + d[2]*d[2]) + q->f->softening2;
        const double v2 = w[0]*w[0] + w[1]*w[1] + w[2]*w[2];
        const double X = v2/(rs2*q->f->G*S);
        const double dlog_X = 2.*(w[0]*b[0] + w[1]*b[1] + w[2]*b[2])/v2 - 2.*(d[0]*w[0] + d[1]*w[1] + d[2]*w[2])/rs2
            - 1.5*(S_i*pi->dlog_pull + S_j*pj->dlog_pull)/S;
        const double X2 = X*X;
        Q = X2*X2;
        dQ = PFVI_ENCOUNTER_FAST_POWER*dlog_X*Q;
        if (!isfinite(Q) || !isfinite(dQ)){
            return 1;
        }
    }
    const double R = R_i + R_j + Q;
    if (!(R > 0.)){
        return 0;
    }
    // A weight below `least` (the term would be negligible): no pow().
    const double x = R/(1. + R);
    if (!weight_reaches(x, least, q->order)){
        return 0;
    }
    *weight = pow(x, q->exponent);
    *dlog = q->exponent*(R_i*dlog_i + R_j*dlog_j + dQ)/(R*(1. + R));
    return isfinite(*weight) && isfinite(*dlog);
}

// An encounter term of one pair (or image): relative position d, velocity
// w, acceleration b, mu = G (m_i + m_j); nothing if the pair is bound or the
// term could not reach `negligible` (it is at most the crossing rate).
static void encounter_term(const double d[3], const double w[3], const double b[3], double mu,
        const struct pfvi_field* f, double negligible, const struct encounter_pair* pair, struct density_sum* sum){
    const double rs2 = (d[0]*d[0] + d[1]*d[1] + d[2]*d[2]) + f->softening2;
    const double v2 = w[0]*w[0] + w[1]*w[1] + w[2]*w[2];
    // Bound (q^2 = v^2 rs/mu <= 2, written without a root), or not a number: no term.
    if (!(v2*v2*rs2 > 4.*mu*mu)){
        return;
    }
    const double P = d[0]*w[0] + d[1]*w[1] + d[2]*w[2];
    // cos^2 of the angle between d and w: 1 approaching or receding on a
    // straight line, 0 at closest approach.
    const double C = P*P/(v2*rs2);
    const double boost = 1. + PFVI_ENCOUNTER_APPROACH*C;
    // The term is below nu_cr (1 + c C): negligible if that is.
    if (!(v2*boost*boost > negligible*negligible*rs2)){
        return;
    }
    double weight = 1., dlog_weight = 0.;
    // The weight the term needs to reach `negligible` (it is below nu_cr (1 + c C) weight).
    const double least = negligible*sqrt(rs2/v2)/boost;
    if (!encounter_weight(pair, d, w, b, least, &weight, &dlog_weight)){
        return;
    }
    const double rs = sqrt(rs2);
    const double q = sqrt(v2*rs/mu);     // nu_cr/nu_ff
    const double nu_ff = sqrt(mu/(rs2*rs));
    const double term = nu_ff*(q - M_SQRT2)*boost*weight;
    if (!(term > negligible) || !isfinite(term)){
        return;
    }
    const double wb = w[0]*b[0] + w[1]*b[1] + w[2]*b[2];
    const double db = d[0]*b[0] + d[1]*b[1] + d[2]*b[2];
    // d log q/dt = (w.b)/v^2 + (d.w)/(2 rs^2); d log nu_ff/dt = -3/2 (d.w)/rs^2;
    // d(d.w)/dt = v^2 + d.b.
    const double dlog_q = wb/v2 + 0.5*P/rs2;
    const double dC = 2.*P*(v2 + db)/(v2*rs2) - 2.*C*(wb/v2 + P/rs2);
    const double dlog = -1.5*P/rs2 + (q/(q - M_SQRT2))*dlog_q + PFVI_ENCOUNTER_APPROACH*dC/boost + dlog_weight;
    if (isfinite(dlog)){
        density_add(sum, term, dlog, 1.);
    }
}

// encounter_term and encounter_weight for the pairs (i, j0 .. j0 + n - 1)
// without ghost boxes, their arithmetic four pairs at a time in vector lanes
// (each lane the scalar expressions, in their order: the same bits), and
// their tests, choices and sums pair by pair in the scalar loop's order.
// The pairs whose two early tests all fail (bound; below `negligible` at
// the block's start, which only grows within a scan) are left at those.
struct encounter_scan {
    const struct reb_particle* p;
    const struct pfvi_end_state* start;
    size_t N;
    const struct pfvi_field* f;
    const struct pfvi_partner* partners;
    double exponent;    // 1/(2s - 2); 0: unweighted
    int order;          // 2s - 2
};

static inline __attribute__((always_inline)) void encounter_block(const struct encounter_scan* e, size_t i,
        int i_attracts, size_t j0, size_t n, struct density_sum* sum){
    const struct reb_particle* const p = e->p;
    const struct pfvi_field* const f = e->f;
    struct lanes_block bl;
    block_at(f, p, e->N, j0, n, &bl);
    const struct reb_vec6d* const sh = &f->images[0];
    const pfvi_lanes d0 = (bl.x + lanes_of(sh->x)) - lanes_of(p[i].x), d1 = (bl.y + lanes_of(sh->y)) - lanes_of(p[i].y),
        d2 = (bl.z + lanes_of(sh->z)) - lanes_of(p[i].z);
    const pfvi_lanes w0 = (bl.vx + lanes_of(sh->vx)) - lanes_of(p[i].vx),
        w1 = (bl.vy + lanes_of(sh->vy)) - lanes_of(p[i].vy), w2 = (bl.vz + lanes_of(sh->vz)) - lanes_of(p[i].vz);
    const pfvi_lanes mu = lanes_of(f->G)*(lanes_of(p[i].m) + bl.m);
    const pfvi_lanes rs2 = (d0*d0 + d1*d1 + d2*d2) + lanes_of(f->softening2);
    const pfvi_lanes v2 = w0*w0 + w1*w1 + w2*w2;
    const pfvi_lanes bound_lhs = v2*v2*rs2, bound_rhs = lanes_of(4.)*mu*mu;
    const pfvi_lanes P = d0*w0 + d1*w1 + d2*w2;
    const pfvi_lanes C = P*P/(v2*rs2);
    const pfvi_lanes boost = lanes_of(1.) + lanes_of(PFVI_ENCOUNTER_APPROACH)*C;
    const pfvi_lanes near_lhs = v2*boost*boost;
    const double negligible0 = PFVI_DENSITY_NEGLIGIBLE*sum->largest;
    const pfvi_lanes near_rhs = lanes_of(negligible0)*lanes_of(negligible0)*rs2;
    int any = 0;
    for (size_t l=0; l<n; l++){
        any |= (bound_lhs[l] > bound_rhs[l]) && (near_lhs[l] > near_rhs[l]);
    }
    if (!any){
        return;
    }
    // The relative accelerations, and each j's partner pull and frequency.
    const double* const ai = acceleration_of(p, e->start, i);
    const struct pfvi_partner* const pi = &e->partners[i];
    pfvi_lanes b0, b1, b2, pull_j, dlog_pull_j, S_j;
    for (int l=0; l<4; l++){
        const size_t j = j0 + (((size_t)l < n) ? (size_t)l : 0);
        const double* const aj = acceleration_of(p, e->start, j);
        b0[l] = aj[0] - ai[0]; b1[l] = aj[1] - ai[1]; b2[l] = aj[2] - ai[2];
        const struct pfvi_partner* const pj = &e->partners[j];
        pull_j[l] = pj->pull;
        dlog_pull_j[l] = pj->dlog_pull;
        S_j[l] = (pj->pull > 0.) ? pj->stiffness : 0.;
    }
    pfvi_lanes root_ratio;     // sqrt(rs2/v2), for `least`
    pfvi_lanes rs;
    for (int l=0; l<4; l++){
        root_ratio[l] = sqrt(rs2[l]/v2[l]);
        rs[l] = sqrt(rs2[l]);
    }
    // encounter_weight's pull ratios (pull_ratio: its rd2 is rs2, and -d, -w
    // give the same squares and products) and crossing rate.
    const pfvi_lanes two_P_rs2 = lanes_of(2.)*P/rs2;
    const pfvi_lanes R_i = (bl.m/rs2)/lanes_of(pi->pull);
    const pfvi_lanes dlog_i = -lanes_of(pi->dlog_pull) - two_P_rs2;
    const pfvi_lanes R_j = (lanes_of(i_attracts ? p[i].m : 0.)/rs2)/pull_j;
    const pfvi_lanes dlog_j = -dlog_pull_j - two_P_rs2;
    const double S_i = (pi->pull > 0.) ? pi->stiffness : 0.;
    const pfvi_lanes S = lanes_of(S_i) + S_j;
    const pfvi_lanes X = v2/(rs2*lanes_of(f->G)*S);
    const pfvi_lanes wb = w0*b0 + w1*b1 + w2*b2;
    const pfvi_lanes dlog_X = lanes_of(2.)*wb/v2 - two_P_rs2
        - lanes_of(1.5)*(lanes_of(S_i*pi->dlog_pull) + S_j*dlog_pull_j)/S;
    const pfvi_lanes X2 = X*X;
    const pfvi_lanes Q = X2*X2;
    const pfvi_lanes dQ = lanes_of(PFVI_ENCOUNTER_FAST_POWER)*dlog_X*Q;
    // encounter_term's term (before its weight) and rate (before the weight's).
    pfvi_lanes q, nu_ff;
    const pfvi_lanes q2 = v2*rs/mu, nu2 = mu/(rs2*rs);
    for (int l=0; l<4; l++){
        q[l] = sqrt(q2[l]);
        nu_ff[l] = sqrt(nu2[l]);
    }
    const pfvi_lanes base = nu_ff*(q - lanes_of(M_SQRT2))*boost;
    const pfvi_lanes db = d0*b0 + d1*b1 + d2*b2;
    const pfvi_lanes dlog_q = wb/v2 + lanes_of(0.5)*P/rs2;
    const pfvi_lanes dC = lanes_of(2.)*P*(v2 + db)/(v2*rs2) - lanes_of(2.)*C*(wb/v2 + P/rs2);
    const pfvi_lanes dlog_base = lanes_of(-1.5)*P/rs2 + (q/(q - lanes_of(M_SQRT2)))*dlog_q
        + lanes_of(PFVI_ENCOUNTER_APPROACH)*dC/boost;
    for (size_t l=0; l<n; l++){
        const size_t j = j0 + l;
        const struct pfvi_partner* const pj = &e->partners[j];
        const double negligible = PFVI_DENSITY_NEGLIGIBLE*sum->largest;
        if (!(i_attracts || p[j].m > 0.) || !(bound_lhs[l] > bound_rhs[l])
                || !(near_lhs[l] > negligible*negligible*rs2[l])){
            continue;
        }
        double weight = 1., dlog_weight = 0.;
        const double least = negligible*root_ratio[l]/boost[l];
        // encounter_weight: 1 where the pair is either body's tightest (or
        // a ratio or the crossing rate is not finite).
        if (e->exponent > 0. && pi->pull > 0. && !(pi->j == j && pi->image == 0)
                && pj->pull > 0. && !(pj->j == i && pj->image == 0)){
            const double Ri = (p[j].m > 0.) ? R_i[l] : 0., dlog_Ri = (p[j].m > 0.) ? dlog_i[l] : 0.;
            const double m_i = i_attracts ? p[i].m : 0.;
            const double Rj = (m_i > 0.) ? R_j[l] : 0., dlog_Rj = (m_i > 0.) ? dlog_j[l] : 0.;
            const int fast = (S[l] > 0.);
            const double Ql = fast ? Q[l] : 0., dQl = fast ? dQ[l] : 0.;
            if (isfinite(Ri) && isfinite(Rj) && (!fast || (isfinite(Ql) && isfinite(dQl)))){
                const double R = Ri + Rj + Ql;
                if (!(R > 0.)){
                    continue;
                }
                const double x = R/(1. + R);
                if (!weight_reaches(x, least, e->order)){
                    continue;
                }
                weight = pow(x, e->exponent);
                dlog_weight = e->exponent*(Ri*dlog_Ri + Rj*dlog_Rj + dQl)/(R*(1. + R));
                if (!(isfinite(weight) && isfinite(dlog_weight))){
                    continue;
                }
            }
        }
        const double term = base[l]*weight;
        if (!(term > negligible) || !isfinite(term)){
            continue;
        }
        const double dlog = dlog_base[l] + dlog_weight;
        if (isfinite(dlog)){
            density_add(sum, term, dlog, 1.);
        }
    }
}

// gamma_s of the Kepler terms' eccentricity factor: at a fixed kappa the
// error per orbit grows like (1 - e)^(-beta_s) (measured); the factor
// (1 - e^2)^(-beta_s/(2s - 2)) evens it out.
static double eccentricity_exponent(int s){
    static const double beta[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_BETA;
    return beta[s]/(2.*s - 2.);
}

// The factor's largest value (1 - E2_MAX)^(-gamma_s) for each s, made once
// as the library loads (by the same pow the density called for it on every
// evaluation before: the same bits).
static double factor_max_of[PFVI_STAGES_MAX + 1];

static void __attribute__((constructor)) factor_max_init(void){
    for (int s=2; s<=PFVI_STAGES_MAX; s++){
        factor_max_of[s] = pow(1. - PFVI_DENSITY_E2_MAX, -eccentricity_exponent(s));
    }
}

PFVI_VECTOR_CLONES
int pfvi_step_density(const struct reb_particle* p, const struct pfvi_end_state* start, size_t N,
        const struct pfvi_field* f, int s, struct pfvi_partner* partners, double* sigma, double* dlog_sigma,
        struct pfvi_lead_orbit* lead){
    const double gamma = eccentricity_exponent(s);
    *sigma = 0.;
    *dlog_sigma = 0.;
    if (lead){
        lead->term = 0.;
    }
    pfvi_partner_search(p, N, f, partners);
    if (!(f->G > 0.)){
        return 0;
    }
    struct density_sum sum = {0., 0., 0.};
    const double factor_max = factor_max_of[s];
    for (size_t i=0; i<N; i++){
        // Each orbit counts twice, once per body of a pair as the
        // calibration of C_s on two bodies had it: a pair of mutual
        // partners is one orbit, seen from the later of the two.
        const size_t j = partners[i].j;
        if (j != SIZE_MAX && j > i && partners[j].j == i && partners[j].image == f->n_images - 1 - partners[i].image
                && single_partner(partners, i) && single_partner(partners, j)){
            continue;
        }
        struct kepler_orbit o;
        double term, dlog;
        if (subsystem_orbit(p, start, i, f, partners, &o)
                && kepler_term(&o, f->softening2, gamma, factor_max, PFVI_DENSITY_NEGLIGIBLE*sum.largest, &term, &dlog)){
            if (lead && term > lead->term){
                memcpy(lead->r, o.r, sizeof(o.r));
                memcpy(lead->v, o.v, sizeof(o.v));
                lead->mu = o.mu;
                lead->term = term;
            }
            density_add(&sum, term, dlog, 2.);
        }
    }
    if (sum.largest > 0.){
        const double exponent = PFVI_ENCOUNTER_WEIGHTED ? 1./(2.*s - 2.) : 0.;
        if (exponent > 0.){
            partner_pulls(p, N, f, partners);
        }
        const size_t n_attracting = (f->N_active < N) ? f->N_active : N;
        const struct encounter_scan scan = {p, start, N, f, partners, exponent, 2*s - 2};
        // Without ghost boxes four pairs at a time (the blocks hold p:
        // pfvi_partner_search filled them); with them pair by pair, each
        // image a pair.
        for (size_t i=0; i<N; i++){
            const int i_attracts = attracts(p, i, n_attracting);
            const size_t before = (i < n_attracting) ? i : n_attracting;
            if (f->n_images == 1){
                for (size_t j0=0; j0<before; j0+=4){
                    encounter_block(&scan, i, i_attracts, j0, (before - j0 < 4) ? before - j0 : 4, &sum);
                }
                continue;
            }
            const double* const ai = acceleration_of(p, start, i);
            for (size_t j=0; j<before; j++){
                if (!(i_attracts || p[j].m > 0.)){
                    continue;
                }
                const double* const aj = acceleration_of(p, start, j);
                const double mu = f->G*(p[i].m + p[j].m);
                const double b[3] = {aj[0] - ai[0], aj[1] - ai[1], aj[2] - ai[2]};
                for (size_t g=0; g<f->n_images; g++){
                    const struct reb_vec6d* const sh = &f->images[g];
                    const double d[3] = {(p[j].x + sh->x) - p[i].x, (p[j].y + sh->y) - p[i].y,
                        (p[j].z + sh->z) - p[i].z};
                    const double w[3] = {(p[j].vx + sh->vx) - p[i].vx, (p[j].vy + sh->vy) - p[i].vy,
                        (p[j].vz + sh->vz) - p[i].vz};
                    const struct encounter_pair pair = {p, f, partners, i, j, g, i_attracts, exponent, 2*s - 2};
                    encounter_term(d, w, b, mu, f, PFVI_DENSITY_NEGLIGIBLE*sum.largest, &pair, &sum);
                }
            }
        }
    }
    if (!(sum.largest > 0.)){
        return 0;
    }
    *sigma = sum.largest*pow(sum.sum, 1./PFVI_DENSITY_NORM);
    *dlog_sigma = sum.weighted/sum.sum;
    return isfinite(*sigma) && isfinite(*dlog_sigma);
}

struct pfvi_stage_spread pfvi_stage_spread(const double (*f)[3], const double (*a)[3], const double* weights, int s){
    double D[3] = {0., 0., 0.}, A2 = 0.;
    for (int k=0; k<s; k++){
        for (int c=0; c<3; c++){
            D[c] += weights[k]*f[k][c];
        }
        const double a2 = a[k][0]*a[k][0] + a[k][1]*a[k][1] + a[k][2]*a[k][2];
        A2 = (a2 > A2) ? a2 : A2;
    }
    return (struct pfvi_stage_spread){D[0]*D[0] + D[1]*D[1] + D[2]*D[2], A2};
}

double pfvi_largest_pull2(const struct reb_particle* p, size_t N, const struct pfvi_field* f, size_t i){
    if (!(f->G > 0.)){
        return 0.;
    }
    const size_t n_attracting = (f->N_active < N) ? f->N_active : N;
    double largest = 0.;
    for (size_t j=0; j<n_attracting; j++){
        if (j == i || !(p[j].m > 0.)){
            continue;
        }
        for (size_t g=0; g<f->n_images; g++){
            const struct reb_vec6d* const sh = &f->images[g];
            const double dx = (p[j].x + sh->x) - p[i].x, dy = (p[j].y + sh->y) - p[i].y,
                dz = (p[j].z + sh->z) - p[i].z;
            const double r2 = (dx*dx + dy*dy + dz*dz) + f->softening2;
            // (G m_j/r^2)^2, with G m_j/r^2 formed first (its square
            // overflows later than m_j^2 or r^4 would).
            const double pull = f->G*p[j].m/r2;
            const double pull2 = pull*pull;
            largest = (pull2 > largest) ? pull2 : largest;
        }
    }
    return isfinite(largest) ? largest : 0.;
}

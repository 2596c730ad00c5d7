/**
 * pfvi_step.c: the one stepping skeleton every scheme runs on (a scheme is
 * a table, struct pfvi_scheme): fit every particle before anything is
 * written, advance, check that every particle is finite, keep what the trial
 * found; commit it if the step is taken. A trial commits nothing, so the
 * step control can try as many as it needs; a refused trial is rolled back.
 */
#include <math.h>
#include "pfvi.h"

static const struct pfvi_scheme* pfvi_scheme_of(const struct pfvi_state* st){
    return (st->options.stages == 2) ? &pfvi_two_point_scheme : &pfvi_stages_scheme;
}

// A frequency taken from the motion (curvature, radial, mean motion) agrees
// with the pull a particle feels to within its orbit's shape; a fixed one can
// be anything (issue 27), and a fitted step whose harmonic part is far from
// the motion's can grow a deviation geometrically (docs/method.md). So with
// a fixed omega each particle's step, as fitted, is checked on the pull it
// feels at the start, a = -W^2 d towards its centre: a step whose map of
// (d, w) is unstable is refused (rolled back, fault recorded). A particle at
// its centre has no W and is not checked.
static int fixed_frequency_stable(struct reb_simulation* r, struct pfvi_state* st, const struct pfvi_scheme* scheme,
        size_t N, double t0, double h){
    const struct reb_particle* const p0 = st->start;
    for (size_t i=0; i<N; i++){
        const struct pfvi_centre* const c = &st->centre[i];
        const double d[3] = {p0[i].x - c->x[0], p0[i].y - c->x[1], p0[i].z - c->x[2]};
        if (d[0] == 0. && d[1] == 0. && d[2] == 0.){
            continue;
        }
        const double* const a = st->end[i].a;
        const double relative[3] = {a[0] - c->acc[0], a[1] - c->acc[1], a[2] - c->acc[2]};
        const double W = pfvi_radial_frequency(d, relative);
        const double half_trace = scheme->half_trace(st, i, h, W*W);
        if (fabs(half_trace) > 1. + PFVI_STABILITY_SLACK){
            pfvi_roll_back(r, st, N, t0);
            const double t = fabs(half_trace);
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_UNSTABLE, .particle = i, .h = h, .t0 = t0,
                .value = scheme->fitted_omega(st, i), .bound = W, .n = (size_t)st->options.stages,
                .growth = (t - 1.) + sqrt((t - 1.)*(t + 1.))};
            return 0;
        }
    }
    return 1;
}

enum pfvi_trial pfvi_trial_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h){
    const struct pfvi_scheme* const scheme = pfvi_scheme_of(st);
    st->statistics.n_attempts++;
    st->trial.variational_evaluations = 0;
    st->trial.variational_unconverged = 0;
    st->trial.megno_dY = 0.;
    st->trial.megno_Y_integral = 0.;
    st->trial.solve_recovered = 0;
    st->trial.stage_failed = 0;
    if (!scheme->prepare(st, h)){
        pfvi_roll_back(r, st, N, t0);
        return PFVI_TRIAL_ERROR;
    }
    // Fit every particle before anything is written. Particles sharing
    // omega (all of them for "none" or a fixed omega) share the work.
    uint64_t n_limited = 0;
    double omega_min = INFINITY, omega_max = 0.;
    double omega_last = NAN;
    enum pfvi_fit_status status_last = PFVI_FIT_OK;
    for (size_t i=0; i<N; i++){
        const double omega = st->omega_fit[i];
        enum pfvi_fit_status status;
        if (i > 0 && omega == omega_last){
            scheme->copy_fit(st, i, i - 1);
            status = status_last;
        }else{
            status = scheme->fit(st, i, omega, h);
        }
        omega_last = omega;
        status_last = status;
        if (status == PFVI_FIT_POLE){
            pfvi_roll_back(r, st, N, t0);
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_POLE, .particle = i, .value = omega*h,
                .n = (size_t)st->options.stages};
            return PFVI_TRIAL_ERROR;
        }
        n_limited += (status == PFVI_FIT_LIMITED);
        const double fitted = scheme->fitted_omega(st, i);
        omega_min = fmin(omega_min, fitted);
        omega_max = fmax(omega_max, fitted);
    }

    if (st->options.frequency == PFVI_FREQUENCY_FIXED && st->options.fitting != PFVI_FITTING_NONE
            && !fixed_frequency_stable(r, st, scheme, N, t0, h)){
        return PFVI_TRIAL_ERROR;
    }

    const enum pfvi_trial trial = scheme->advance(r, st, N, t0, h);
    if (trial != PFVI_TRIAL_OK){
        return trial;
    }
    const size_t bad = pfvi_first_not_finite(r->particles, N);
    if (bad != SIZE_MAX){
        pfvi_roll_back(r, st, N, t0);
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_NOT_FINITE, .particle = bad, .t0 = t0};
        return PFVI_TRIAL_ERROR;
    }
    st->trial.n_limited = n_limited;
    st->trial.omega_min = omega_min;
    st->trial.omega_max = omega_max;
    return PFVI_TRIAL_OK;
}

void pfvi_give_up(struct pfvi_state* st, struct pfvi_fault fault){
    st->fault = (st->stage_fault.kind != PFVI_FAULT_NONE) ? st->stage_fault : fault;
}

void pfvi_commit_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h){
    pfvi_scheme_of(st)->commit(r, st, N, h);
    struct pfvi_statistics* const stats = &st->statistics;
    const uint64_t rounds = st->trial.rounds;
    stats->n_iterations += rounds;
    stats->iterations_max = (rounds > stats->iterations_max) ? rounds : stats->iterations_max;
    stats->n_u_limited += st->trial.n_limited;
    stats->n_variational_evaluations += st->trial.variational_evaluations;
    stats->n_variational_unconverged += (uint64_t)st->trial.variational_unconverged;
    stats->n_solve_recovered += (uint64_t)st->trial.solve_recovered;
    stats->omega_min = st->trial.omega_min;
    stats->omega_max = st->trial.omega_max;
}

// The resolution of the pulls on particle i beyond its partner's (issue 40):
// a weak pull that varies within the step (a retrograde body passing
// Jupiter, 1e-3 of the Sun's pull) leaves an error proportional to its
// size F times (h/tau)^(2s - 2), while its share of the stages' leading
// coefficient D_p is F (h/tau)^(s - 1)/(s - 1)!: measured against the net
// acceleration alone (|D_p|/A) it reads sqrt(F/A) times too fine. Returned
// (weak_pull_ratio) as |D_p|/sqrt(A F), the ratio a Kepler pull of the same
// error shows (A: the largest stage acceleration, or the largest pull if
// pull2 >= 0), times sqrt(PFVI_WEAK_PULL_MARGIN); 0 without a massive
// partner. Only for the symmetric control, which refreshed st->partners for
// this step. The stages are measured once (weak_pull_of) and the ratio
// taken for each pull2 asked (a second one when the largest pull is
// measured), so the stage loop runs once per particle; the same loop gives
// the spread of the particle's stage accelerations (pfvi_stage_spread(a, a,
// weights, s)), which it would otherwise make again.
struct weak_pull {
    int any;            // 0: no massive partner, the ratio is 0 (and net not measured)
    double A2;          // the largest stage acceleration's square
    double F2;          // the largest rest's (the pulls beyond the partner's) square
    double D[3];        // sum_k w_k rest_k (pfvi_stage_resolution's D of the rest)
    struct pfvi_stage_spread net;   // pfvi_stage_spread(a, a, weights, s)
};

// Component c of the stages k[0 .. 3] as lanes. (Always inlined, so the
// vector return's ABI, which differs with and without AVX, never applies;
// GCC warns of it at the file's end, hence the pragma for the file.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
static inline __attribute__((always_inline)) pfvi_lanes stage_lanes(const double (*x)[3], const int k[4], int c){
    return (pfvi_lanes){x[k[0]][c], x[k[1]][c], x[k[2]][c], x[k[3]][c]};
}

// The stage loop of weak_pull_of with four stages as vector lanes, each lane
// the scalar expressions (the same bits). Lanes past s repeat the block's
// first stage (finite values): the largest squares are kept lane by lane
// (a repeated stage changes no maximum, nor does the order: the squares are
// never -0, and a NaN is passed over either way), and D's sums are taken
// over the stages in order, as pfvi_stage_spread takes them (D of the
// rest and of a).
PFVI_VECTOR_CLONES
static void weak_pull_stages(const double (*xi)[3], const double (*xj)[3], const double (*a)[3], int s,
        const double shift[3], double Gm, double softening2, const double* weights, struct weak_pull* out){
    pfvi_lanes A2 = {0., 0., 0., 0.}, F2 = {0., 0., 0., 0.};
    double D[3] = {0., 0., 0.}, Da[3] = {0., 0., 0.};
    for (int k0=0; k0<s; k0+=4){
        const int n = (s - k0 < 4) ? s - k0 : 4;
        const int k1 = (n > 1) ? k0 + 1 : k0, k2 = (n > 2) ? k0 + 2 : k0, k3 = (n > 3) ? k0 + 3 : k0;
        const int k[4] = {k0, k1, k2, k3};
        pfvi_lanes d[3], rest[3];
        for (int c=0; c<3; c++){
            d[c] = (stage_lanes(xj, k, c) + shift[c]) - stage_lanes(xi, k, c);
        }
        const pfvi_lanes al[3] = {stage_lanes(a, k, 0), stage_lanes(a, k, 1), stage_lanes(a, k, 2)};
        const pfvi_lanes r2 = (d[0]*d[0] + d[1]*d[1] + d[2]*d[2]) + softening2;
        pfvi_lanes root;
        for (int l=0; l<4; l++){
            root[l] = sqrt(r2[l]);
        }
        const pfvi_lanes pull = Gm/(r2*root);
        for (int c=0; c<3; c++){
            rest[c] = al[c] - pull*d[c];
        }
        const pfvi_lanes a2 = al[0]*al[0] + al[1]*al[1] + al[2]*al[2];
        const pfvi_lanes f2 = rest[0]*rest[0] + rest[1]*rest[1] + rest[2]*rest[2];
        // (x > y ? x : y) lane by lane.
        A2 = lanes_where(a2 > A2, a2, A2);
        F2 = lanes_where(f2 > F2, f2, F2);
        const pfvi_lanes w = {weights[k0], weights[k1], weights[k2], weights[k3]};
        for (int c=0; c<3; c++){
            const pfvi_lanes p = w*rest[c], pa = w*al[c];
            if (n == 4){
                D[c] = (((D[c] + p[0]) + p[1]) + p[2]) + p[3];
                Da[c] = (((Da[c] + pa[0]) + pa[1]) + pa[2]) + pa[3];
            }else{
                for (int l=0; l<n; l++){
                    D[c] += p[l];
                    Da[c] += pa[l];
                }
            }
        }
    }
    double A2_max = 0., F2_max = 0.;
    for (int l=0; l<4; l++){
        A2_max = (A2[l] > A2_max) ? A2[l] : A2_max;
        F2_max = (F2[l] > F2_max) ? F2[l] : F2_max;
    }
    out->A2 = A2_max;
    out->F2 = F2_max;
    for (int c=0; c<3; c++){
        out->D[c] = D[c];
    }
    out->net = (struct pfvi_stage_spread){Da[0]*Da[0] + Da[1]*Da[1] + Da[2]*Da[2], A2_max};
}

// (Inlined, as GCC did before the resolution's loop grew: as a call of its
// own, 88 more instructions a step at N = 3; inlined, 7.)
static inline __attribute__((always_inline)) struct weak_pull weak_pull_of(const struct reb_simulation* r, const struct pfvi_state* st, size_t N, size_t i,
        const struct pfvi_field* field, const double* weights, const double (*a)[3]){
    struct weak_pull w = {0, 0., 0., {0., 0., 0.}, {0., 0.}};
    const struct pfvi_partner* const q = &st->partners[i];
    if (q->j >= N || q->j == i || q->image >= field->n_images || !(r->particles[q->j].m > 0.) || !(field->G > 0.)){
        return w;
    }
    if (N < 3 && field->n_images == 1 && !r->additional_forces){
        return w;    // two bodies alone: no pull but the partner's
    }
    const struct pfvi_scheme* const scheme = pfvi_scheme_of(st);
    double xi[PFVI_STAGES_MAX][3], xj[PFVI_STAGES_MAX][3];
    scheme->stage_positions(r, st, i, xi);
    scheme->stage_positions(r, st, q->j, xj);
    const struct reb_vec6d* const sh = &field->images[q->image];
    const double shift[3] = {sh->x, sh->y, sh->z};
    weak_pull_stages((const double (*)[3])xi, (const double (*)[3])xj, a, st->options.stages, shift,
        field->G*r->particles[q->j].m, field->softening2, weights, &w);
    w.any = 1;
    return w;
}

static double weak_pull_ratio(const struct weak_pull* w, double pull2){
    if (!w->any){
        return 0.;
    }
    const double A2 = fmax(w->A2, pull2), F2 = w->F2;
    if (!(F2 > 0.) || !(A2 > 0.) || !(F2 < A2)){
        return 0.;    // no weaker pull: the check against A covers it
    }
    // |D_p|/F from the rest's own stage values (pfvi_stage_resolution of the
    // rest's spread against itself: its largest square is F2).
    const double dp = sqrt((w->D[0]*w->D[0] + w->D[1]*w->D[1] + w->D[2]*w->D[2])/F2);
    // Held PFVI_WEAK_PULL_MARGIN times below a Kepler orbit's error (the
    // error goes as the ratio squared).
    const double ratio = sqrt(PFVI_WEAK_PULL_MARGIN)*dp*sqrt(sqrt(F2/A2));
    return isfinite(ratio) ? ratio : 0.;
}

struct pfvi_resolution pfvi_trial_resolution(const struct reb_simulation* r, const struct pfvi_state* st, size_t N,
        double h, const struct pfvi_field* field, double pull_above, int residual, double motion){
    const struct pfvi_scheme* const scheme = pfvi_scheme_of(st);
    // The barycentric weights of the nodes: the rule's, or (0, 1)'s for s = 2.
    static const double two_point[2] = {-1., 1.};
    static const double two_point_nodes[2] = {0., 1.};
    const int s = st->options.stages;
    const double* const weights = (s == 2) ? two_point : st->rule.lagrange;
    const double* const nodes = (s == 2) ? two_point_nodes : st->rule.c;
    struct pfvi_resolution worst = {0., SIZE_MAX, 0., 0};
    for (size_t i=0; i<N; i++){
        double a[PFVI_STAGES_MAX][3], f[PFVI_STAGES_MAX][3];
        scheme->stage_accelerations(r, st, i, a);
        const double omega = residual ? scheme->fitted_omega(st, i) : 0.;
        if (omega != 0.){
            // What the quadrature carries of a fitted step: the force less
            // the harmonic pull -omega^2 d its path holds exactly, about
            // the particle's centre c(t) (pfvi_centre.c).
            double x[PFVI_STAGES_MAX][3];
            scheme->stage_positions(r, st, i, x);
            const struct pfvi_centre* const c = &st->centre[i];
            const double w2 = omega*omega;
            for (int k=0; k<s; k++){
                for (int m=0; m<3; m++){
                    const double d = (x[k][m] - c->x[m]) - pfvi_centre_shift(c, nodes[k]*h, m);
                    f[k][m] = (a[k][m] - c->acc[m]) + w2*d;
                }
            }
        }
        const double (*const values)[3] = (omega != 0.) ? (const double (*)[3])f : (const double (*)[3])a;
        // (The weak-pull check's stage loop measures the net resolution too.)
        const int weak_check = field && !residual && omega == 0. && st->partners;
        const struct weak_pull w = weak_check ? weak_pull_of(r, st, N, i, field, weights, (const double (*)[3])a)
            : (struct weak_pull){0, 0., 0., {0., 0., 0.}, {0., 0.}};
        // (the stages measured once; each ratio below is of this spread)
        const struct pfvi_stage_spread spread = w.any ? w.net
            : pfvi_stage_spread(values, (const double (*)[3])a, weights, s);
        double ratio = pfvi_stage_resolution(&spread, 0.);
        double pull2 = -1.;    // the largest pull's square, once measured
        if (field && ratio > pull_above){
            // Unresolved against its net acceleration: measured against the
            // largest pull on it at either end (pfvi_timescales.c).
            const double pull0 = pfvi_largest_pull2(st->start, N, field, i);
            const double pull1 = pfvi_largest_pull2(r->particles, N, field, i);
            pull2 = fmax(pull0, pull1);
            ratio = pfvi_stage_resolution(&spread, pull2);
        }
        worst.own = (ratio > worst.own || ratio != ratio) ? ratio : worst.own;
        for (int k=1; motion > 0. && !worst.varies && k<s; k++){
            // (!=: a NaN varies too)
            worst.varies = (a[k][0] != a[0][0]) | (a[k][1] != a[0][1]) | (a[k][2] != a[0][2]);
        }
        if (motion > 0. && ratio > pull_above){
            // An acceleration that vanishes where a force region ends goes
            // as a power of the distance to its edge, so against itself a
            // step that ends at the edge reads the same at any length: the
            // steps crept up to the edge and were cut down to t's rounding
            // (a body leaving a slab of 2 (1 - (d/W)^2)^2 raised at
            // t = 10.2; a hostile trial). Against the motion it is resolved.
            const struct reb_particle* const p0 = &st->start[i];
            const struct reb_particle* const p1 = &r->particles[i];
            const double v2 = fmax(p0->vx*p0->vx + p0->vy*p0->vy + p0->vz*p0->vz,
                p1->vx*p1->vx + p1->vy*p1->vy + p1->vz*p1->vz);
            const double floor2 = motion*motion*v2/(h*h);
            ratio = pfvi_stage_resolution(&spread, fmax(pull2, floor2));
        }
        if (weak_check){
            const double weak = weak_pull_ratio(&w, pull2);
            if (weak > ratio && field && weak > pull_above && pull2 < 0.){
                // Measured against the largest pull too, as above.
                const double pull0 = pfvi_largest_pull2(st->start, N, field, i);
                const double pull1 = pfvi_largest_pull2(r->particles, N, field, i);
                const double again = weak_pull_ratio(&w, fmax(pull0, pull1));
                ratio = fmax(ratio, again);
            }else{
                ratio = fmax(ratio, weak);
            }
        }
        if (ratio > worst.ratio || (ratio != ratio && worst.ratio == worst.ratio)){
            worst.ratio = ratio;
            worst.particle = i;
        }
    }
    return worst;
}

double pfvi_resolution_error(int s, double u){
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    static const double resolution_constant[PFVI_STAGES_MAX + 1] = PFVI_RESOLUTION_CONSTANTS;
    return constant[s]*pow(u/resolution_constant[s], 2.*s - 2.);
}

double pfvi_resolution_of_error(int s, double error){
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    static const double resolution_constant[PFVI_STAGES_MAX + 1] = PFVI_RESOLUTION_CONSTANTS;
    return resolution_constant[s]*pow(error/constant[s], 1./(2.*s - 2.));
}

// (s - 1)!
static double factorial_of(int n){
    double f = 1.;
    for (int k=2; k<=n; k++){
        f *= k;
    }
    return f;
}

// The largest angle h n_q (n_q = (mu (1 + e)/q^3)^(1/2), the rate at
// pericentre q) over the bodies whose bound two-body orbit about their
// partner (at the step's start p) reaches its pericentre within the step:
// the densities at a step's ends do not see a pericentre between them (e =
// 0.9 at 3 steps per orbit: ends 2.6 radians apart, the body ejected).
static double pericentre_span(const struct reb_particle* p, size_t N, const struct pfvi_field* f,
        const struct pfvi_partner* partners, double h, size_t* worst){
    double largest = 0.;
    for (size_t i=0; i<N; i++){
        const size_t j = partners[i].j;
        if (j >= N || partners[i].image >= f->n_images){
            continue;
        }
        const struct reb_vec6d* const sh = &f->images[partners[i].image];
        const double r[3] = {p[i].x - (p[j].x + sh->x), p[i].y - (p[j].y + sh->y), p[i].z - (p[j].z + sh->z)};
        const double v[3] = {p[i].vx - (p[j].vx + sh->vx), p[i].vy - (p[j].vy + sh->vy), p[i].vz - (p[j].vz + sh->vz)};
        const double mu = f->G*(p[i].m + p[j].m);
        const double rn = sqrt(r[0]*r[0] + r[1]*r[1] + r[2]*r[2]);
        const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
        const double rv = r[0]*v[0] + r[1]*v[1] + r[2]*v[2];
        const double inv_a = 2./rn - v2/mu;
        if (!(mu > 0.) || !(rn > 0.) || !(inv_a > 0.)){
            continue;   // unbound or degenerate: no pericentre ahead to time
        }
        const double a = 1./inv_a;
        const double n = sqrt(mu*inv_a*inv_a*inv_a);
        const double ec = 1. - rn*inv_a, es = rv/sqrt(mu*a);   // e cos E, e sin E
        const double e = sqrt(ec*ec + es*es);
        const double M = atan2(es, ec) - es;                    // in (-pi, pi]: 0 at pericentre
        // Time from the start to the pericentre in the step's direction.
        const double to_peri = (h > 0.) ? ((M <= 0.) ? -M : 2.*M_PI - M)/n : ((M >= 0.) ? M : 2.*M_PI + M)/n;
        if (!(to_peri <= fabs(h)) || !(e < 1.)){
            continue;
        }
        const double q = a*(1. - e);
        const double span = fabs(h)*sqrt(mu*(1. + e)/(q*q*q));
        // (>=: of a mutual pair, the later body, usually the lighter, is named)
        if (span >= largest && isfinite(span)){
            largest = span;
            *worst = i;
        }
    }
    return largest;
}

int pfvi_fixed_step_check(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        struct pfvi_fixed_check* out){
    const int s = st->options.stages;
    struct pfvi_field field;
    if (!pfvi_field_of(r, st, &field)){
        pfvi_roll_back(r, st, N, t0);
        return 0;
    }
    // Particles whose stages imply the warning level against their net
    // acceleration are measured against the pulls on them too.
    const double u_warn = pfvi_resolution_of_error(s, PFVI_FIXED_WARN);
    const double above = pow(u_warn, s - 1.)/factorial_of(s - 1);
    const struct pfvi_resolution worst = pfvi_trial_resolution(r, st, N, h, &field, above, 1, 0.);
    out->u = pow(factorial_of(s - 1)*worst.ratio, 1./(s - 1.));
    out->error = pfvi_resolution_error(s, out->u);
    out->particle = worst.particle;
    out->kappa = 0.;
    out->pericentre = SIZE_MAX;
    out->refuse = 0;
    out->saturated = 0;
    // The largest u any stage values give: |D| <= sum |w_k| A.
    double weights_sum = 2.;
    if (s > 2){
        weights_sum = 0.;
        for (int k=0; k<s; k++){
            weights_sum += fabs(st->rule.lagrange[k]);
        }
    }
    const double u_bound = pow(factorial_of(s - 1)*weights_sum, 1./(s - 1.));
    // (Also at the warning level: the estimate saturates, and a step across
    // the pericentre of e = 0.9 at 3 steps per orbit read 0.093 per orbit
    // while it ejected the body: issue 40.)
    out->saturated = !(out->u <= PFVI_FIXED_GATE*u_bound);
    if (out->saturated || out->error > PFVI_FIXED_WARN){
        // The stages' estimate is bounded (|D| <= sum |w_k| A): at s = 8 it
        // stays below 0.01 however long the step, and a step over several
        // orbits can converge to a root that is no motion at all. So a step
        // they do not show well resolved is also measured on the density of
        // the adaptive control at its two ends: a step longer than
        // PFVI_FIXED_KAPPA_MAX/sigma covers more than an orbit of the
        // fastest time scale, and is refused.
        double sigma0, sigma1, g;
        pfvi_step_density(st->start, st->end, N, &field, s, st->partners, &sigma0, &g, NULL);
        pfvi_step_density(r->particles, NULL, N, &field, s, st->partners, &sigma1, &g, NULL);
        const double sigma = fmax(sigma0, sigma1);
        size_t passing = SIZE_MAX;
        const double peri = pericentre_span(st->start, N, &field, st->partners, h, &passing);
        out->kappa = fmax(fabs(h)*sigma, peri);
        out->pericentre = (peri > fabs(h)*sigma) ? passing : SIZE_MAX;
        if (out->kappa > PFVI_FIXED_KAPPA_MAX){
            out->refuse = 1;
        }
    }
    st->statistics.error_estimate = out->error;
    if (out->refuse){
        pfvi_roll_back(r, st, N, t0);
        const int peri = (out->pericentre != SIZE_MAX);
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_UNRESOLVED_FIXED,
            .particle = peri ? out->pericentre : out->particle, .flag = peri, .h = h,
            .t0 = t0, .value = out->error, .bound = out->kappa};
    }
    return !out->refuse;
}

int pfvi_var_start_finite(const struct reb_simulation* r, struct pfvi_state* st, double t0){
    const struct reb_particle* const pv = r->particles_var;
    const size_t v = pfvi_first_not_finite(pv, st->var_N);
    if (v == SIZE_MAX){
        return 1;
    }
    const double values[7] = {pv[v].x, pv[v].y, pv[v].z, pv[v].vx, pv[v].vy, pv[v].vz, pv[v].m};
    int field = 0;
    while (field < 6 && isfinite(values[field])){
        field++;
    }
    st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_VARIATIONAL, .particle = v, .n = st->var_real[v],
        .flag = field, .value = values[field], .t0 = t0};
    return 0;
}

/**
 * pfvi_control.c: adaptive steps from osculating circles (K&V, "Frequency
 * Evaluation and Error Control"; the geometry is pfvi_osculating.c).
 *
 * Two controllers use K&V's estimate:
 *  - "seed": accept the step if the estimate is at most epsilon, else retry it
 *    shorter; propose the next step by the standard rule
 *    h 0.9 (epsilon/estimate)^(1/3), bounded in growth and shrink.
 *  - "reversible": solve estimate(y_n, y_n+1(h)) = epsilon for h (secant on
 *    log h), with every particle fitted to the mean of its curvature
 *    frequencies at the two ends. Both conditions are symmetric in y_n and
 *    y_n+1, so the step taken backward from y_n+1 is the same step: the
 *    time-symmetric step selection of Hut, Makino & McMillan (1995, ApJ 443,
 *    L93), here with K&V's estimate as the step function.
 * Both keep u = omega h <= u_max with the curvature frequency (or the fixed
 * omega), whatever the fitting, and propose the next step through r->dt, so
 * that REBOUND's exact_finish_time can shorten it as it does for IAS15.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "pfvi.h"

// The frequency of the controller's u bound: the fixed omega, or the curvature one.
static double control_omega(const struct pfvi_state* st, const struct pfvi_osculating* c){
    return (st->options.frequency == PFVI_FREQUENCY_FIXED) ? st->options.omega : c->omega;
}

// What a trial step tells the controller: the largest estimate, whether any
// particle had circles at both ends, and the largest u bound frequency at the
// end (seed) or averaged over the ends (reversible). Fills omega_end.
struct control_view {
    double error;
    double noise;          // round-off level of the largest estimate
    int informed;
    double omega_end_max;
    double omega_mean_max;
};

static struct control_view control_look(const struct reb_simulation* r, struct pfvi_state* st, size_t N){
    const struct reb_particle* const ps = r->particles;
    struct control_view view = {0., 0., 0, 0., 0.};
    for (size_t i=0; i<N; i++){
        const double v[3] = {ps[i].vx, ps[i].vy, ps[i].vz};
        const double a[3] = {ps[i].ax, ps[i].ay, ps[i].az};
        struct pfvi_osculating c1;
        pfvi_osculating_circle(v, a, &c1);
        const struct pfvi_osculating* const c0 = &st->osculating_start[i];
        const int comparable = pfvi_osculating_comparable(c0, &c1);
        view.informed |= comparable;
        double noise = 0.;
        const double x0[3] = {st->start[i].x, st->start[i].y, st->start[i].z};
        const double x1[3] = {ps[i].x, ps[i].y, ps[i].z};
        const double error = comparable ? pfvi_osculating_error(x0, c0, x1, &c1, &noise) : 0.;
        if (error > view.error){
            view.error = error;
            view.noise = noise;
        }
        st->omega_end[i] = c1.omega;
        const double w1 = control_omega(st, &c1);
        view.omega_end_max = fmax(view.omega_end_max, w1);
        view.omega_mean_max = fmax(view.omega_mean_max, 0.5*(control_omega(st, c0) + w1));
    }
    if (st->options.frequency == PFVI_FREQUENCY_FIXED && st->options.omega > 0.){
        view.informed = 1;
    }
    return view;
}

// |h| at most u_max / omega, sign kept.
static double control_u_bound(const struct pfvi_state* st, double h, double omega){
    if (omega > 0. && fabs(h)*omega > st->options.u_max){
        return copysign(st->options.u_max/omega, h);
    }
    return h;
}

static double control_seed(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double omega_start_max){
    double h = control_u_bound(st, r->dt, omega_start_max);
    int rejections = 0;
    struct control_view view = {0., 0., 0, 0., 0.};
    for (;;){
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        double shrink = 0.5;  // a stage solve that did not converge: halve the step
        if (trial == PFVI_TRIAL_OK){
            view = control_look(r, st, N);
            if (view.error <= st->options.epsilon){
                break;
            }
            pfvi_roll_back(r, st, N, t0);
            shrink = fmax(PFVI_CONTROL_SHRINK_MIN, PFVI_CONTROL_SAFETY*pow(st->options.epsilon/view.error, 1./PFVI_CONTROL_ORDER));
        }
        st->statistics.n_rejected++;
        st->statistics.n_solve_halved += (trial == PFVI_TRIAL_NOT_CONVERGED);
        rejections++;
        const double h_next = h*shrink;
        if (rejections >= PFVI_CONTROL_MAX_REJECTIONS || t0 + h_next == t0){
            pfvi_give_up(st, (struct pfvi_fault){.kind = PFVI_FAULT_REJECTED, .t0 = t0, .h = h,
                .value = (trial == PFVI_TRIAL_OK) ? view.error : NAN});
            return 0.;
        }
        h = h_next;
    }
    pfvi_commit_step(r, st, N, h);
    st->statistics.error_estimate = view.error;
    double grow = 1.;  // no particle on a curve: nothing to go on, keep the step
    if (view.informed){
        grow = (view.error > 0.) ? PFVI_CONTROL_SAFETY*pow(st->options.epsilon/view.error, 1./PFVI_CONTROL_ORDER)
                                 : PFVI_CONTROL_GROW_MAX;
        grow = fmin(PFVI_CONTROL_GROW_MAX, fmax(PFVI_CONTROL_SHRINK_MIN, grow));
        if (rejections){
            grow = fmin(grow, 1.);
        }
    }
    r->dt = control_u_bound(st, h*grow, view.omega_end_max);
    return h;
}

// The reversible step: h and the fitted frequencies solve
//   F(h) = max(estimate/epsilon, |h| max_i omega_mean_i / u_max) = 1,
//   omega_fit_i = mean of the particle's frequency at the two ends,
// both to within PFVI_REVERSIBLE_TOLERANCE or the estimate's round-off,
// whichever is larger (the estimate is a difference of first-order
// quantities). F need not be monotonic in h (the estimate changes sign across
// a curvature extremum), so the root is kept bracketed once it is: secant
// steps in log F against log |h| through the last two trials, bisection in
// log |h| when the secant leaves the bracket. r->dt
// caps the step (REBOUND's exact finish time relies on it); a capped step is
// taken if F <= 1 there.
static double control_reversible(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double omega_start_max){
    const double cap = fabs(r->dt), sign = copysign(1., r->dt);
    double h = cap;
    if (st->dt_reversible != 0. && copysign(1., st->dt_reversible) == sign && fabs(st->dt_reversible) < cap){
        h = fabs(st->dt_reversible);
    }
    h = fabs(control_u_bound(st, h, omega_start_max));
    // The mean of the two ends is the curvature frequency in the simulation frame:
    // only that model (K&V's) is fitted symmetrically; the others keep the start's.
    const int fitted = (st->options.fitting != PFVI_FITTING_NONE && st->options.frequency == PFVI_FREQUENCY_CURVATURE
        && st->options.centre == PFVI_CENTRE_ORIGIN);
    double lo = 0., hi = INFINITY;                // F(lo) < 1 < F(hi) once bracketed
    double log_h_prev = NAN, log_F_prev = NAN;    // the previous trial, for the secant
    struct control_view view = {0., 0., 0, 0., 0.};
    double F = NAN;
    int solved = 0, trials = 0;
    while (trials < PFVI_REVERSIBLE_MAX_TRIALS){
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        if (trial == PFVI_TRIAL_NOT_CONVERGED){
            st->statistics.n_rejected++;
            st->statistics.n_solve_halved++;
            hi = h;
            log_h_prev = NAN;
            h *= 0.5;
            if (t0 + sign*h == t0){
                break;
            }
            continue;  // not counted as a trial of the step equation
        }
        trials++;
        view = control_look(r, st, N);
        const double error_ratio = view.error/st->options.epsilon;
        const double u_ratio = h*view.omega_mean_max/st->options.u_max;
        F = fmax(error_ratio, u_ratio);
        // The frequencies this h asks for, and how far they are from those used.
        double change = 0., omega_scale = 0.;
        if (fitted){
            for (size_t i=0; i<N; i++){
                const double mean = 0.5*(st->osculating_start[i].omega + st->omega_end[i]);
                change = fmax(change, fabs(mean - st->omega_fit[i]));
                omega_scale = fmax(omega_scale, mean);
            }
            change = (omega_scale > 0.) ? change/omega_scale : 0.;
        }
        const double noise = (error_ratio >= u_ratio && view.error > 0.) ? view.noise/view.error : 0.;
        const double tolerance = fmax(PFVI_REVERSIBLE_TOLERANCE, 4.*noise);
        const int frequencies_solved = change <= tolerance;
        if (!view.informed || F == 0.){
            // Nothing but the cap limits the step.
            if (h == cap && frequencies_solved){
                solved = 1;
                break;
            }
        }else if (frequencies_solved && (fabs(F - 1.) <= tolerance || (h == cap && F <= 1.))){
            solved = 1;
            break;
        }
        pfvi_roll_back(r, st, N, t0);
        if (fitted){
            for (size_t i=0; i<N; i++){
                st->omega_fit[i] = 0.5*(st->osculating_start[i].omega + st->omega_end[i]);
            }
        }
        double h_next;
        if (!view.informed || F == 0.){
            lo = h;
            log_h_prev = NAN;
            h_next = fmin(cap, PFVI_CONTROL_GROW_MAX*h);
        }else{
            const double log_h = log(h), log_F = log(F);
            if (F < 1.){
                lo = h;
            }else{
                hi = h;
            }
            // Secant through this trial and the previous one; the estimate's
            // order if there is none or its slope is implausible.
            double slope = (error_ratio >= u_ratio) ? PFVI_CONTROL_ORDER : 1.;
            if (isfinite(log_h_prev) && log_h != log_h_prev){
                const double secant = (log_F - log_F_prev)/(log_h - log_h_prev);
                if (secant >= 0.3 && secant <= 30.){
                    slope = secant;
                }
            }
            h_next = h*exp(-log_F/slope);
            h_next = fmin(fmax(h_next, 0.1*h), 10.*h);
            if (!(h_next > lo && h_next < hi)){
                h_next = (lo > 0.) ? sqrt(lo*hi) : 0.5*hi;  // bisection in log h
            }
            h_next = fmin(h_next, cap);
            log_h_prev = log_h;
            log_F_prev = log_F;
        }
        if (t0 + sign*h_next == t0){
            break;
        }
        h = h_next;
    }
    if (!solved && lo > 0.){
        // Not solved in time: take the largest step tried that met epsilon.
        // It is not time-symmetric; counted in n_asymmetric.
        h = lo;
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        if (trial == PFVI_TRIAL_OK){
            view = control_look(r, st, N);
            solved = 1;
            st->statistics.n_asymmetric++;
        }
    }
    if (!solved){
        pfvi_give_up(st, (struct pfvi_fault){.kind = PFVI_FAULT_UNSOLVED, .t0 = t0, .rounds = (uint64_t)trials,
            .h = sign*h, .value = F});
        return 0.;
    }
    h *= sign;
    pfvi_commit_step(r, st, N, h);
    st->statistics.error_estimate = view.error;
    st->dt_reversible = h;
    // The next cap: room to grow, as in the seed controller.
    r->dt = view.informed ? PFVI_CONTROL_GROW_MAX*h : h;
    return h;
}

// The epsilon the symmetric control works to: the request, held within
// what s stages can deliver (PFVI_EPSILON_FLOORS below, kappa's cap above).
static double symmetric_epsilon(const struct pfvi_options* o){
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    static const double floor_[PFVI_STAGES_MAX + 1] = PFVI_EPSILON_FLOORS;
    const double top = constant[o->stages]*pow(PFVI_KAPPA_MAX, 2.*o->stages - 2.);
    return fmin(fmax(o->epsilon, floor_[o->stages]), top);
}

// kappa = (epsilon/C_s)^(1/(2s - 2)): the step in units of 1/sigma.
static double symmetric_kappa(const struct pfvi_options* o){
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    return pow(symmetric_epsilon(o)/constant[o->stages], 1./(2.*o->stages - 2.));
}

// (s - 1)!: u = ((s - 1)! |D|/A)^(1/(s - 1)) is h nu for an acceleration
// that varies like cos(nu t) (its Taylor term of degree s - 1).
static double factorial(int n){
    double f = 1.;
    for (int k=2; k<=n; k++){
        f *= k;
    }
    return f;
}

// The resolution u of a trial step of h (pfvi.h, PFVI_RESOLUTION_CONSTANTS):
// a particle whose u against its net acceleration is above u_low, the
// lowest u a decision below looks at, is measured against the pulls on it
// too (pfvi_trial_resolution: a cancelled acceleration is not an unresolved one).
// (above: pow(u_low, s - 1)/(s - 1)!, from symmetric_constants)
static double symmetric_resolution(const struct reb_simulation* r, const struct pfvi_state* st, size_t N, double h,
        const struct pfvi_field* field, double above){
    const int s = st->options.stages;
    return pow(factorial(s - 1)*pfvi_trial_resolution(r, st, N, h, field, above, 0, 0.).ratio, 1./(s - 1.));
}

// The resolution of a trial step read with both ends' partners: the weak-pull
// check measures each body against its partner's pull, and a body whose
// partner changes within the step would be measured against one partner
// going one way and another coming back, so that a step on the threshold is
// taken whole one way and retaken the other (tests/test_split.py's planets
// at 1e-8: one step judged 1.007 and 1.112 of the Kepler worst, 25 of 30
// round trips more than 1e-9 off). The larger of the two, as a reversed step
// reads the same pair. (st->partners: the trial's end, from pfvi_step_density.)
static double symmetric_resolution_both(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h,
        const struct pfvi_field* field, double above){
    const double u_end = symmetric_resolution(r, st, N, h, field, above);
    int same = 1;
    for (size_t i=0; i<N; i++){
        same &= (st->partners[i].j == st->partners_start[i].j) & (st->partners[i].image == st->partners_start[i].image);
    }
    if (same){
        return u_end;
    }
    struct pfvi_partner* const end = st->partners;
    st->partners = st->partners_start;
    const double u_start = symmetric_resolution(r, st, N, h, field, above);
    st->partners = end;
    return fmax(u_end, u_start);
}

// kappa, the effective epsilon, u_target and the resolution check's
// threshold for the options' s and epsilon: made when either changed since
// the last step (the same arguments, the same results: the memo saves the
// powers, not their bits).
static const struct pfvi_symmetric_constants* symmetric_constants(struct pfvi_state* st){
    static const double resolution_constant[PFVI_STAGES_MAX + 1] = PFVI_RESOLUTION_CONSTANTS;
    const struct pfvi_options* const o = &st->options;
    struct pfvi_symmetric_constants* const m = &st->symmetric_constants;
    if (m->stages != o->stages || memcmp(&m->epsilon, &o->epsilon, sizeof(o->epsilon)) != 0){
        const int s = o->stages;
        m->stages = s;
        m->epsilon = o->epsilon;
        m->kappa = symmetric_kappa(o);
        m->epsilon_effective = symmetric_epsilon(o);
        m->u_target = resolution_constant[s]*m->kappa;
        const double u_low = m->u_target/PFVI_RESOLUTION_SLACK;
        m->above = pow(u_low, s - 1.)/factorial(s - 1);
    }
    return m;
}

// Where a symmetric step starts on the track (struct pfvi_state): the
// density rho of the interval it lies in, the interval's length kappa/rho,
// and what of it remains in the step's direction.
struct track_position {
    double rho;
    double length;
    double done;        // from the end the step entered the interval at
    double remaining;
};

// Whether the saved track belongs to this kappa (a changed epsilon or s, or
// particles edited or added since, start it afresh).
static int symmetric_on_track(const struct pfvi_state* st, double kappa){
    return st->rho > 0. && isfinite(st->rho) && st->track_kappa == kappa
        && (st->rho_sign == 1. || st->rho_sign == -1.);
}

// A track no step could have left (rho far from lambda sigma, lambda out of
// range: set by hand or read from an edited archive) is discarded.
static void symmetric_discard_implausible(struct pfvi_state* st, double sigma){
    if (!(st->density_scale >= 1. && st->density_scale <= PFVI_DENSITY_SCALE_MAX)){
        st->density_scale = 1.;
        st->rho = 0.;
    }
    const double ratio = st->rho/(st->density_scale*sigma);
    if (st->rho != 0. && !(ratio >= 1./PFVI_TRACK_RATIO_MAX && ratio <= PFVI_TRACK_RATIO_MAX)){
        st->rho = 0.;
    }
}

// A Kepler orbit's eccentric anomaly at mean anomaly M (Newton's iteration).
static double eccentric_anomaly(double M, double e){
    double E = (e < 0.8) ? M : M_PI;
    for (int k=0; k<64; k++){
        const double d = (E - e*sin(E) - M)/(1. - e*cos(E));
        E -= d;
        if (fabs(d) < 1e-12){
            break;
        }
    }
    return E;
}

// A fresh track in direction `sign` starts at the state on the curve the
// track begun at the leading orbit's last pericentre follows (rho = lambda
// sigma there): that track is run along the Kepler orbit to the state
// (pfvi.h, PFVI_TRACK_START_SHARE), and its log(rho/(lambda sigma)) is
// interpolated between the grid points around the state; *ratio is rho/
// (lambda sigma) for the fresh track's first interval, a grid point at the
// state as before. Returns 0 where it does not apply (no bound orbit of e
// >= TRACK_START_E leads the density, or its orbit takes more than
// TRACK_START_STEPS steps): the start is then lambda sigma + kappa g/2.
static __attribute__((noinline, cold)) int pericentre_start(const struct reb_simulation* r, struct pfvi_state* st,
        size_t N, double kappa, double sign, double* ratio){
    struct pfvi_field field;
    struct pfvi_lead_orbit lead;
    double sigma = 0., g = 0.;
    if (!pfvi_field_of(r, st, &field)
            || !pfvi_step_density(r->particles, NULL, N, &field, st->options.stages, st->partners_scratch, &sigma, &g,
                &lead)
            || !(lead.term > 0.)){
        return 0;
    }
    // The other terms (the leading pair counts twice) are a small part.
    const double others = pow(sigma/lead.term, PFVI_DENSITY_NORM);
    if (!(others <= PFVI_TRACK_START_SHARE)){
        return 0;
    }
    const double* const x = lead.r;
    const double* const v = lead.v;
    const double rn = sqrt(x[0]*x[0] + x[1]*x[1] + x[2]*x[2]);
    const double v2 = v[0]*v[0] + v[1]*v[1] + v[2]*v[2];
    const double rv = x[0]*v[0] + x[1]*v[1] + x[2]*v[2];
    const double inverse_a = 2./rn - v2/lead.mu;
    if (!(inverse_a > 0.) || !(rn > 0.)){
        return 0;
    }
    const double a = 1./inverse_a;
    const double ecos = 1. - rn/a, esin = rv/sqrt(lead.mu*a);
    const double e = hypot(ecos, esin);
    if (!(e >= PFVI_TRACK_START_E && e < 1.)){
        return 0;
    }
    // In units of the orbit (a = 1, mean motion 1): lambda sigma is c tau(M),
    // tau = ((1 - e cos E)^2 + s2)^(-3/4) (c from the state), its rate
    // -3/2 e sin E/((1 - e cos E)^2 + s2); a way back is the way forward on
    // the mirrored orbit.
    const double s2 = field.softening2/(a*a);
    double M0 = atan2(esin, ecos) - esin;
    M0 = (M0 < 0.) ? M0 + 2.*M_PI : M0;
    M0 = (sign < 0. && M0 > 0.) ? 2.*M_PI - M0 : M0;
    const double q0 = rn/a;
    const double c = st->density_scale*sigma/(sqrt(lead.mu*inverse_a*inverse_a*inverse_a)*pow(q0*q0 + s2, -0.75));
    // The steps an orbit takes, about (c/kappa) times the integral of tau
    // over the mean anomaly (the integral of (1 - e cos E)^(-1/2) over E,
    // by the midpoint rule on 16 points): beyond TRACK_START_STEPS, not run.
    double integral = 0.;
    for (int k=0; k<16; k++){
        const double E = (k + 0.5)*M_PI/8.;
        const double q = 1. - e*cos(E);
        integral += q*pow(q*q + s2, -0.75);
    }
    if (!(c*integral*M_PI/8./kappa <= PFVI_TRACK_START_STEPS)){
        return 0;
    }
    double M = 0., tau = pow((1. - e)*(1. - e) + s2, -0.75), rho = c*tau;
    for (int k=0; k<2*PFVI_TRACK_START_STEPS; k++){
        const double h = kappa/rho;
        const double E1 = eccentric_anomaly(M + h, e);
        const double q = 1. - e*cos(E1), d2 = q*q + s2;
        const double tau1 = pow(d2, -0.75);
        const double rho1 = rho - 1.5*kappa*e*sin(E1)/d2;
        if (!(rho1 > 0.)){
            return 0;
        }
        if (M + h > M0){
            const double w = (M0 - M)/h;
            *ratio = exp((1. - w)*log(rho/(c*tau)) + w*log(rho1/(c*tau1)));
            return isfinite(*ratio) && *ratio > 0.5 && *ratio < 2.;
        }
        M += h;
        rho = rho1;
        tau = tau1;
    }
    return 0;
}

// The track at a step in direction `sign` from a state of density sigma and
// rate g: a retrace on a reversal, the rest of an interval a capped step
// left, the next interval (the Hairer & Soderlind update), or a fresh start
// (at `start` times lambda sigma where that is given: pericentre_start).
static struct track_position symmetric_position(const struct pfvi_state* st, double sign, double kappa,
        double sigma, double g, const double* start){
    struct track_position t = {0., 0., 0., 0.};
    const int track = symmetric_on_track(st, kappa);
    if (track && sign != st->rho_sign){
        // Reversed: back over what the last steps went of this interval.
        t.rho = st->rho;
        t.length = kappa/t.rho;
        t.remaining = st->track_at_end ? t.length : st->track_done;
        t.done = st->track_at_end ? 0. : t.length - st->track_done;
        return t;
    }
    if (track && !st->track_at_end){
        t.rho = st->rho;
        t.length = kappa/t.rho;
        t.done = st->track_done;
        t.remaining = t.length - t.done;
        if (t.remaining > 0.){
            return t;
        }
    }
    if (track){
        t.rho = st->steady.hold ? st->rho : st->rho + sign*kappa*g;
    }
    if (!(t.rho > 0.) || !isfinite(t.rho)){
        const double scaled = st->density_scale*sigma;
        t.rho = start ? scaled*(*start) : scaled + 0.5*sign*kappa*g;
        t.rho = (t.rho > 0. && isfinite(t.rho)) ? t.rho : scaled;
    }
    t.length = kappa/t.rho;
    t.done = 0.;
    t.remaining = t.length;
    return t;
}

// symmetric_position for a step from the time t_at: the rest of an
// interval a cap left below t's last place is no step (a cap a few places
// short of the interval: the proposal of a track since restarted, sim.dt
// after a density jump, measured 16 places short with a drag force), so the
// interval is taken as ended there and the next one begins (without this
// the run stopped: "the step dt = 5.55e-17 does not change t").
static struct track_position symmetric_position_at(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        double t_at, double sign, double kappa, double sigma, double g){
    double start;
    // Not after a close approach restarted the track (the state is inside
    // or just past the encounter, where the leading orbit's curve says
    // little: the retrograde crosser from 8 phases ended up to 7.1 and 3.1
    // epsilon a n off at 1e-7 and 1e-8 with it, 2.5 and 0.62 without; the
    // build before 7.1 and 3.3), nor for a second edit in a row (a mass lost
    // every step: 37 steps for the unedited run's 35 with it, 36 without).
    const int placed = !symmetric_on_track(st, kappa) && !st->track_restarted
        && !(st->track_edited && st->track_edited_before) && pericentre_start(r, st, N, kappa, sign, &start);
    struct track_position t = symmetric_position(st, sign, kappa, sigma, g, placed ? &start : NULL);
    if (t.done > 0. && t.remaining > 0. && t_at + sign*t.remaining == t_at){
        st->track_at_end = 1;
        t = symmetric_position(st, sign, kappa, sigma, g, NULL);
    }
    return t;
}

// Whether the full interval of the track just ended at r->t (of length
// `length`, crossed in direction `sign`) lies outside the time the track's
// mismatch average has seen (track_seen_lo ... track_seen_hi, extended if
// so). Only such intervals enter the average: a reversal retraces the
// intervals the way out averaged, and the average kept as it was there
// makes the drift correction fire where it fired, never anew (averaged
// again on the way back, an average of -0.094 at the turn reached -0.1:
// e = 0.68 from apocentre came back with one asymmetric step, t 15 off the
// start; undone exactly, A = (A' - w m)/(1 - w) grows the doubles' error
// by 1/(1 - w) per interval).
static int symmetric_interval_unseen(struct pfvi_state* st, double t_end, double length, double sign){
    const double middle = t_end - 0.5*sign*length;
    if (sign > 0. && middle > st->track_seen_hi){
        st->track_seen_hi = t_end;
        return 1;
    }
    if (sign < 0. && middle < st->track_seen_lo){
        st->track_seen_lo = t_end;
        return 1;
    }
    return 0;
}

static void steady_forget(struct pfvi_state* st){
    st->steady.hold = 0;
    st->steady.n = 0;
    st->steady.entry_sign = st->steady.exit_sign = 0.;
}

// Whether an interval of length `length` ended at t, the time of a recorded
// hold's start or end (the grid a retrace lands on carries t's rounding).
static int steady_at(double t, double t_event, double length){
    return fabs(t - t_event) <= 1e-6*length;
}

// The time scale 2 pi/sqrt(G (m_i + m_j)/r^3) of the loosest partner pair
// (the slowest orbit a body makes about its partner), 0 without pairs.
static double steady_slowest(const struct pfvi_state* st, size_t N, double G){
    double least = INFINITY;
    for (size_t i=0; i<N; i++){
        const double k = st->partners[i].stiffness;
        least = (st->partners[i].j != SIZE_MAX && k > 0. && k < least) ? k : least;
    }
    return (isfinite(least) && G > 0.) ? 2.*M_PI/sqrt(G*least) : 0.;
}

// The steady track at the end of a full interval (length `length`, density
// lambda sigma = d at its end, crossed in direction sign; unseen: beyond
// what the track has seen). On seen intervals a reversal meets the holds the
// way out began and ended and undoes them there (a second reversal redoes
// them); on unseen ones the window starts and ends holds. Returns 1 where
// rho jumped (a step that is not time-symmetric).
static int steady_update(struct pfvi_state* st, size_t N, double G, double t, double length, double sign, double d,
        int unseen){
    if (!unseen){
        if (st->steady.hold && st->steady.entry_sign == -sign && steady_at(t, st->steady.entry_t, length)){
            st->steady.hold = 0;
            st->rho = st->steady.entry_rho;
            st->rho_sign = st->steady.entry_sign;
        }else if (!st->steady.hold && st->steady.entry_sign == sign && steady_at(t, st->steady.entry_t, length)){
            st->steady.hold = 1;
            st->rho = st->steady.entry_rho;
        }else if (!st->steady.hold && st->steady.exit_sign == -sign && steady_at(t, st->steady.exit_t, length)){
            st->steady.hold = 1;
            st->rho = st->steady.exit_held;
            st->rho_sign = st->steady.exit_sign;
        }else if (st->steady.hold && st->steady.exit_sign == sign && steady_at(t, st->steady.exit_t, length)){
            st->steady.hold = 0;
            st->rho = st->steady.exit_after;
        }
        return 0;
    }
    if (!(d > 0.) || N < PFVI_STEADY_BODIES){
        st->steady.n = 0;
        return 0;
    }
    if (st->steady.hold){
        const int above = d > st->rho*(1. + PFVI_STEADY_EXCESS);
        if (above || d*(1. + PFVI_STEADY_BAND) < st->rho){
            // Above: the track goes on from rho (the density's rate takes
            // it up); far below, rho moves onto the density.
            const double after = above ? st->rho : d;
            st->steady.hold = 0;
            st->steady.n = 0;
            st->steady.exit_t = t;
            st->steady.exit_sign = sign;
            st->steady.exit_held = st->rho;
            st->steady.exit_after = after;
            const int jumped = (after != st->rho);
            st->rho = after;
            return jumped;
        }
        return 0;
    }
    const double slowest = steady_slowest(st, N, G);
    if (st->steady.n == 0){
        st->steady.t0 = t;
        st->steady.span = 0.;
    }
    st->steady.lo = (st->steady.n == 0) ? d : fmin(st->steady.lo, d);
    st->steady.hi = (st->steady.n == 0) ? d : fmax(st->steady.hi, d);
    st->steady.span = fmax(st->steady.span, slowest);
    st->steady.n += (st->steady.n < PFVI_STEADY_WINDOW);
    if (st->steady.hi > st->steady.lo*(1. + PFVI_STEADY_BAND) || !(slowest > 0.)){
        st->steady.n = 1;
        st->steady.t0 = t;
        st->steady.span = slowest;
        st->steady.lo = st->steady.hi = d;
        return 0;
    }
    // A full window, over a cycle of its slowest orbit, and rho at its top.
    if (st->steady.n < PFVI_STEADY_WINDOW || fabs(t - st->steady.t0) < st->steady.span || st->rho < st->steady.hi){
        return 0;
    }
    st->steady.hold = 1;
    st->steady.n = 0;
    st->steady.entry_t = t;
    st->steady.entry_sign = sign;
    st->steady.entry_rho = st->rho;
    return 0;
}

// The track as a step finds it, for the replay log (struct pfvi_replay).
static void replay_keep(const struct pfvi_state* st, struct pfvi_replay* e){
#define PFVI_FIELD_KEEP(type, name) e->name = st->name;
    PFVI_TRACK_FIELDS(PFVI_FIELD_KEEP)
#undef PFVI_FIELD_KEEP
}

static void replay_restore(struct pfvi_state* st, const struct pfvi_replay* e){
#define PFVI_FIELD_RESTORE(type, name) st->name = e->name;
    PFVI_TRACK_FIELDS(PFVI_FIELD_RESTORE)
#undef PFVI_FIELD_RESTORE
}

// Which count of replay_count an entry taken in direction sign is in.
static int replay_side(double sign){
    return (sign > 0.) ? 0 : 1;
}

void pfvi_replay_clear(struct pfvi_state* st){
    st->replay_n = 0;
    st->replay_count[0] = st->replay_count[1] = 0;
}

static void replay_push(struct pfvi_state* st, const struct pfvi_replay* e){
    if (st->replay_n == PFVI_REPLAY_MAX){
        st->replay_count[replay_side(st->replay[st->replay_first].sign)]--;
        st->replay_first = (st->replay_first + 1) % PFVI_REPLAY_MAX;   // the oldest goes
        st->replay_n--;
    }
    st->replay[(st->replay_first + st->replay_n) % PFVI_REPLAY_MAX] = *e;
    st->replay_n++;
    st->replay_count[replay_side(e->sign)]++;
}

// The logged step a step from t0 in direction sign retraces: the newest
// entry taken the other way (entries this direction logged since lie above
// it), ending (within the track's rounding of t) where this step starts;
// its index in the ring, or -1.
static long replay_due(const struct pfvi_state* st, double t0, double sign){
    if (st->replay_count[replay_side(-sign)] == 0){
        return -1;   // (a run that has not turned: no scan of its own entries)
    }
    for (size_t k=st->replay_n; k-- > 0;){
        const struct pfvi_replay* const e = &st->replay[(st->replay_first + k) % PFVI_REPLAY_MAX];
        if (e->sign == sign){
            continue;
        }
        const double length = fabs(e->t_end - e->t_start);
        return (fabs(t0 - e->t_end) <= PFVI_REPLAY_T_SLACK*length) ? (long)k : -1;
    }
    return -1;
}

// Removes entry k (0: the oldest) from the ring.
static void replay_remove(struct pfvi_state* st, size_t k){
    st->replay_count[replay_side(st->replay[(st->replay_first + k) % PFVI_REPLAY_MAX].sign)]--;
    for (size_t m=k; m+1<st->replay_n; m++){
        st->replay[(st->replay_first + m) % PFVI_REPLAY_MAX] = st->replay[(st->replay_first + m + 1) % PFVI_REPLAY_MAX];
    }
    st->replay_n--;
}

// A step kept though its stages do not resolve the forces: counted, and
// said once per simulation (kept silently, such steps made a
// velocity-dependent force without its flag 40 times IAS15's error: a
// hostile trial).
static void count_unresolved(struct reb_simulation* r, struct pfvi_state* st, double t0){
    st->statistics.n_unresolved++;
    if (st->unresolved_warned){
        return;
    }
    st->unresolved_warned = 1;
    pfvi_warning(r, "pfvi: step at t = %.6g kept unresolved after " PFVI_STR(PFVI_RESOLUTION_RETRIES)
            " retakes (n_unresolved): epsilon not met there. Forces that jump within a step, or depend on "
            "velocities without sim.force_is_velocity_dependent = 1, do this. Said once.", t0);
}

// A kappa below PFVI_KAPPA_WARN: said once per simulation, with the steps an
// orbit takes at these stages and at the most.
static void warn_small_kappa(struct reb_simulation* r, struct pfvi_state* st, double kappa){
    st->kappa_warned = 1;
    struct pfvi_options most = st->options;
    most.stages = PFVI_STAGES_MAX;
    const double turn = 2.*M_PI;
    pfvi_warning(r, "pfvi: epsilon %.3g at stages = %d takes steps of %.2g radians of the fastest orbit: "
            "about %.2g steps an orbit, more where it is eccentric (stages = %d: about %.2g). Said once per simulation.",
            st->options.epsilon, st->options.stages, kappa, turn/kappa, PFVI_STAGES_MAX, turn/symmetric_kappa(&most));
}

// The shortest |v|/|a| at the step's start over the bodies that move and
// are pulled (0 if none): about the time a body takes to turn.
static double unpaired_time_scale(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    double least = INFINITY;
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const p = &r->particles[i];
        const double* const a = st->end[i].a;
        const double v2 = p->vx*p->vx + p->vy*p->vy + p->vz*p->vz;
        const double a2 = a[0]*a[0] + a[1]*a[1] + a[2]*a[2];
        if (v2 > 0. && a2 > 0.){
            const double tau = sqrt(v2/a2);
            least = (tau < least) ? tau : least;
        }
    }
    return isfinite(least) ? least : 0.;
}

// Without pairs (gravity off, or no massive body: test particles in a
// potential given by additional_forces) there is no density to track. Each
// step is then sized by its own stages: their resolution u (h times the
// rate their forces vary at, the resolution check's measure; of a fitted
// step, of the force its fitted path does not carry) is aimed at
// PFVI_UNPAIRED_AIMS[s] kappa, as an explicit method's embedded estimate steers
// it; not time-symmetric (n_asymmetric). A step above PFVI_UNPAIRED_RETAKE
// times the aim is retaken shorter, one whose solve does not converge at
// half (each counted in n_rejected). Forces that do not vary over a step
// (free motion, a uniform field: u = 0) leave the step as it was, sim.dt at
// the start; a sim.dt below the run's proposal caps one step. Before, the steps were sim.dt whatever epsilon asked: a test
// particle of e = 0.9 in a Kepler potential from additional_forces ended
// 140 off IAS15 at sim.dt = 1 with no warning (a hostile trial).
// Nothing can change the bodies' straight paths: no pair that gravity
// joins (G = 0, gravity off, fewer than two bodies, or no active body with
// mass), no force of the user's or REBOUNDx's and no timestep hook. The
// stages are then exact at any step, and no force region lies ahead for a
// long step to leap. (Contacts are found along each step's path whatever
// its length: pfvi_contact.c. Not with ghost boxes: there a meeting through
// the box's wrap inside a long step was missed, and the output step after
// it refused at the two bodies' one position; a hostile trial.)
static int motion_is_free(const struct reb_simulation* r, size_t N){
    if (r->additional_forces || r->pre_timestep_modifications || r->post_timestep_modifications
            || r->gravity == REB_GRAVITY_CUSTOM || r->N_ghost_x || r->N_ghost_y || r->N_ghost_z){
        return 0;
    }
    if (r->gravity == REB_GRAVITY_NONE || r->G == 0. || N < 2){
        return 1;
    }
    const size_t n_active = (r->N_active < N) ? r->N_active : N;
    for (size_t j=0; j<n_active; j++){
        if (r->particles[j].m != 0.){
            return 0;
        }
    }
    return 1;
}

static double control_unpaired(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double sign, const struct pfvi_symmetric_constants* constants){
    const int s = st->options.stages;
    static const double aim[PFVI_STAGES_MAX + 1] = PFVI_UNPAIRED_AIMS;
    const double u_aim = aim[s]*constants->kappa;
    // An output time does not cap the step (pfvi_output.c shows it), as on
    // the symmetric track: the step is the one this run proposed.
    const int output = st->output_uncapped && st->dt_proposed != 0.;
    double h = output ? fabs(st->dt_proposed) : fabs(r->dt), u = 0., u_last = INFINITY;
    if (st->output_uncapped && st->dt_proposed == 0. && st->dt_first_uncut != 0.){
        // A new simulation's first step, which REBOUND cut to a time within
        // the dt it began with: the run's first step is that dt, as in a
        // single call (before, the cut: after integrate(1e-9), 135 steps
        // against one call's 114, s = 8; a hostile trial).
        h = fabs(st->dt_first_uncut);
    }
    // The step this run proposed where sim.dt caps it below that (REBOUND's
    // cut to an output, the value it restores after one, the user's): a cap
    // holds this step only, so the next grows from the proposal, as the
    // symmetric track goes on after a cap. (Else free motion, u = 0, kept the
    // cap for good: with a post-timestep hook every integrate() starts
    // capped at the step REBOUND restores, 0.001 for a new simulation, and an
    // open box left with one body took 3012 steps for one call's 3.)
    const double proposed = (st->dt_proposed != 0. && h < fabs(st->dt_proposed)) ? fabs(st->dt_proposed) : 0.;
    if (!(st->dt_proposed != 0. && h == fabs(st->dt_proposed))){
        // A step this run did not propose (the first, the user's, REBOUND's
        // restored last step) is at most the shortest |v|/|a| of a moving
        // body: the stages' u saturates on steps far beyond the orbit, so
        // retakes from there shorten too little (sim.dt = 200 from the
        // pericentre of e = 0.99 ejected the body; REBOUND's 0.001 an orbit
        // of a = 3e-4: a hostile trial).
        const double tau = unpaired_time_scale(r, st, N);
        st->dt_free = (st->dt_free == 0.) ? h : st->dt_free;   // (the first: sim.dt)
        h = (tau > 0. && h > tau) ? tau : h;
    }
    int retakes = 0, unresolved = 0;
    size_t first_particle = SIZE_MAX;   // the body the first trial resolved worst
    int own_fired = 0;                  // the first trial retaken for its force's own resolution
    double u_own = 0.;
    struct pfvi_field field;
    for (;;){
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        double h_next = 0.5*h;
        if (trial == PFVI_TRIAL_OK){
            if (!pfvi_field_of(r, st, &field)){
                pfvi_roll_back(r, st, N, t0);
                return 0.;
            }
            // (Of a fitted step, what its fitted path does not carry: the
            // oscillator at its own frequency is exact at any step, and keeps
            // sim.dt, as the seed's fixed steps did.)
            const struct pfvi_resolution res = pfvi_trial_resolution(r, st, N, sign*h, &field, constants->above, 1,
                constants->epsilon_effective);
            u = pow(factorial(s - 1)*res.ratio, 1./(s - 1.));
            u_own = pow(factorial(s - 1)*res.own, 1./(s - 1.));
            if (!res.varies){
                // The same force at every stage (a uniform field) reads the
                // rounding of the weights' sum, not 0: it is free motion.
                // (Else u at that rounding, far below the aim, doubled the
                // steps without bound: 122.5 after 9 steps in a field of
                // 1e-3, and a slab at x = 200 was leapt; a hostile trial.)
                u = u_own = 0.;
            }
            if (!st->unpaired_retaken && retakes == 0 && u_own > PFVI_UNPAIRED_RETAKE*u_aim
                    && st->unpaired_crawl < PFVI_RESOLUTION_RETRIES){
                own_fired = 1;
                // Resolved against the motion only after a retake, of this
                // step or the one before (the steps are closing in on an
                // edge): a first trial whose stages caught only a tail of a
                // force (sim.dt = 100 from 10 before a Gaussian slab) is
                // retaken as before, not let leap it (0.35 off; a hostile trial).
                u = u_own;
            }
            // Retaken while shorter steps resolve the forces better (a first
            // sim.dt far beyond the orbit: the stages' u saturates, so each
            // retake shortens by a bounded factor); kept after
            // RESOLUTION_RETRIES retakes that stopped helping (forces that
            // jump), or after CONTROL_MAX_REJECTIONS in all.
            // Also kept where a retake would be below t's rounding: this
            // step's solve converged, and a shorter one cannot be taken.
            const int coarse = u > PFVI_UNPAIRED_RETAKE*u_aim;
            const int helping = u < PFVI_UNPAIRED_HELPING*u_last;
            h_next = h*fmax(PFVI_CONTROL_SHRINK_MIN, fmin(0.5, u_aim/u));
            unresolved = coarse && ((retakes >= PFVI_RESOLUTION_RETRIES && !helping)
                || retakes >= PFVI_CONTROL_MAX_REJECTIONS
                || (retakes == 0 && st->unpaired_suspect >= PFVI_RESOLUTION_RETRIES && h <= PFVI_CONTROL_GROW_MAX*st->dt_suspect
                    && res.particle + 1 == (size_t)st->suspect_body)
                || t0 + sign*h_next == t0);
            u_last = u;
            if (retakes == 0){
                first_particle = res.particle;
            }
            if (!coarse || unresolved){
                break;
            }
            pfvi_roll_back(r, st, N, t0);
            retakes++;
        }else{
            st->statistics.n_solve_halved++;
        }
        st->statistics.n_rejected++;
        st->statistics.n_asymmetric++;
        h = h_next;
        if (t0 + sign*h == t0){
            pfvi_give_up(st, (struct pfvi_fault){.kind = PFVI_FAULT_NOT_CONVERGED, .n = (size_t)s,
                .value = st->trial.change, .rounds = st->trial.rounds, .t0 = t0});
            return 0.;
        }
    }
    pfvi_commit_step(r, st, N, sign*h);
    st->rho = 0.;
    if (unresolved){
        count_unresolved(r, st, t0);
    }
    // (Counted over the steps in between too, which the proposal keeps as
    // short: a step that resolves its forces near the aim ends the count.)
    st->unpaired_retaken = (retakes > 0);
    // A step retaken for its force's own resolution and then kept as
    // resolved against the motion (u below PFVI_UNPAIRED_SUSPECT of the
    // aim), again and again, is a crawl to where a force vanishes (a slab's
    // far edge, (1 - q^2)^2: each step sized by the distance left, so t
    // converged on the edge and the run was refused at t's rounding, s = 4,
    // epsilon 1e-12). After PFVI_RESOLUTION_RETRIES of them that retake
    // rests until the force is resolved against its own scale or felt.
    {
        const int against_motion = u < PFVI_UNPAIRED_SUSPECT*u_aim && u_own > PFVI_UNPAIRED_RETAKE*u_aim;
        st->unpaired_crawl = !against_motion ? 0 : st->unpaired_crawl + own_fired;
    }
    // (Judged against the motion too, u after a retake, a Gaussian's far
    // tail reads low at any step, so that the retakes of its approach count
    // as a jump's: 205 steps warned unresolved at s = 4, epsilon 1e-6,
    // before the count was one body's and the crawl rule above (3 since).
    // Judged against the force's own scale instead, the count carried over
    // the free motion between compact bumps, and a coarse first trial kept
    // at the next one left 1.3e-5 at epsilon 1e-10, s = 5; a hostile trial.
    // Kept as it was: docs/adaptive.md, "Known limits".)
    // Free motion back at the run's longest free step ends the count: a
    // jump is approached in steps retaken shorter, never at that step, so
    // what counted before belonged to a region now left. (Else the count
    // built up at one compact bump's far edge carried over to the next, and
    // its first coarse trial was kept unresolved at once: six C-infinity
    // bumps ended 1e-3 off at s = 4 and 3.7e-5 at s = 7, epsilon 1e-10.)
    const int low = u < PFVI_UNPAIRED_SUSPECT*u_aim;
    const int left_behind = (u == 0. && retakes == 0 && h >= st->dt_free);
    // The count is one body's: retakes for another body's first trial start
    // it again at that body. (Else the retakes of one body's crawl out of a
    // bump's far edge, counted, let another body's first coarse trial across
    // the next bump's near edge be kept at once: three bodies through four
    // C-infinity bumps ended 3.7e-7 off at s = 4, epsilon 1e-12.)
    const int same_body = (first_particle != SIZE_MAX && (int)first_particle + 1 == st->suspect_body);
    st->unpaired_suspect = (unresolved || !low || left_behind) ? 0
        : (retakes > 0 ? (same_body ? st->unpaired_suspect + 1 : 1) : st->unpaired_suspect);
    // The shortcut keeps only a trial at most twice the last step counted:
    // an approach grows a step that fell short at most twice before its next
    // trial, and a longer trial is not the approach the count saw. (With
    // several bodies one body's count held while another's steps grew
    // back, free motion never came, and a first trial of 0.04 at the next
    // region was kept unresolved at once: three bodies through four bumps
    // ended 1.8e-4 off at s = 3, epsilon 1e-6.)
    st->dt_suspect = (st->unpaired_suspect == 0) ? 0. : (retakes > 0 ? h : st->dt_suspect);
    st->suspect_body = (st->unpaired_suspect == 0) ? 0
        : ((retakes > 0 && first_particle != SIZE_MAX) ? (int)first_particle + 1 : st->suspect_body);
    {
        static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
        static const double resolution_constant[PFVI_STAGES_MAX + 1] = PFVI_RESOLUTION_CONSTANTS;
        st->statistics.error_estimate = constant[s]*pow(u/resolution_constant[s], 2.*s - 2.);
    }
    // The next step: towards the aim, with a margin (PFVI_UNPAIRED_SAFETY)
    // so that a step growing into a faster passage is seldom retaken; at
    // most PFVI_CONTROL_GROW_MAX times this one, and not grown after retakes.
    const double aimed = (u > 0.) ? PFVI_UNPAIRED_SAFETY*u_aim/u : 1.;
    const double factor = fmax(PFVI_CONTROL_SHRINK_MIN, fmin(retakes ? 1. : PFVI_CONTROL_GROW_MAX, aimed));
    double next = h*factor;
    if (proposed > 0. && retakes == 0){
        // A capped step: grown from what the run proposed, not from the cap.
        next = (u > 0.) ? fmax(PFVI_CONTROL_SHRINK_MIN*h, fmin(h*aimed, PFVI_CONTROL_GROW_MAX*proposed)) : proposed;
    }
    if (u == 0. && retakes == 0){
        // Free motion grows back to the longest free step this run took
        // (sim.dt, as it began): never beyond, so that it does not leap a
        // force region the way a step without bound would. (Before, it kept
        // the step it had where a force region ended: a Gaussian slab
        // crossed at sim.dt = 0.5 took 1359 steps to t = 20, now 543.)
        st->dt_free = fmax(st->dt_free, h);
        next = fmax(next, fmin(PFVI_CONTROL_GROW_MAX*h, st->dt_free));
        if (motion_is_free(r, N)){
            // Where nothing can act, grown as far as the run goes, as
            // IAS15's are (else a lone body at REBOUND's sim.dt = 0.001 took
            // 1e7 steps to t = 1e4, and 1e5 hung; a hostile trial).
            next = PFVI_CONTROL_GROW_MAX*fmax(h, proposed);
        }
    }else if (u_own > u){
        // Resolved only against the motion (a force too weak to matter over
        // this step): grown no further than the force's own scale allows,
        // or free motion would. (Without this bound a weak background of
        // 1e-12 sin x let the steps grow to 7.8 and leap a slab; a hostile trial.)
        const double own = h*fmax(PFVI_CONTROL_SHRINK_MIN,
            fmin(retakes ? 1. : PFVI_CONTROL_GROW_MAX, PFVI_UNPAIRED_SAFETY*u_aim/u_own));
        next = fmin(next, fmax(own, fmin(PFVI_CONTROL_GROW_MAX*h, st->dt_free)));
    }
    r->dt = sign*next;
    st->dt_proposed = r->dt;
    return sign*h;
}

// The symmetric step (Hairer & Soderlind 2005, SIAM J. Sci. Comput. 26,
// 1838): the grid of the run has intervals h_n = kappa/rho_n+1/2 with
//     rho_n+1/2 = rho_n-1/2 + kappa G(y_n),   G = d log(sigma)/dt,
// an explicit update that is the same read forward or backward, so that rho
// tracks lambda sigma (pfvi_step_density; lambda = density_scale, 1 unless
// a check below raised it) along the orbit and the steps reverse exactly,
// as long as sigma changes by less than itself over a step (the density's
// terms are built so: pfvi_timescales.c). One stage solve per step.
//
// sim.dt is the step proposed after each step (the rest of the interval,
// or the next interval). A different value (REBOUND shortening a step to
// finish on time, a sampling time, or the user) caps the step: the interval
// is then crossed in more than one step and the track goes on, so that a
// reversal retraces the capped step exactly before it retraces the
// intervals. On the track, the value REBOUND restores after an exact finish
// (the last full step) is not a cap either; off it (a first step, or
// particles edited or added) sim.dt caps the step unless it is REBOUND's
// default and pfvi never proposed one.
//
// Checks, each retaking the step shorter (n_rejected; the step is then not
// time-symmetric, n_asymmetric):
//  - the stage solve did not converge: half the step (the interval goes on);
//  - the density at either end exceeds PFVI_DENSITY_JUMP_MAX/h (a close
//    approach the track could not foresee): half the step, and the track
//    starts afresh after it;
//  - the stages resolve the forces worse than any Kepler orbit does at this
//    kappa (the error they imply above PFVI_RESOLUTION_MAX times the worst
//    there: a time scale the density misses): retaken at the step that
//    would resolve them, at most half the last, and lambda raised by the
//    factor that took. Still unresolved after PFVI_RESOLUTION_RETRIES
//    retakes (a force that jumps within a step, as a tree code's cells do,
//    is resolved by no step), the last is kept, lambda left as it was and
//    the step counted in n_unresolved.
// Lambda falls back towards 1 where whole intervals resolve the forces
// PFVI_RESOLUTION_SLACK times finer than needed (n_asymmetric). Without
// pairs (no gravity, or no massive body): control_unpaired.
static double control_symmetric(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    static const double resolution_constant[PFVI_STAGES_MAX + 1] = PFVI_RESOLUTION_CONSTANTS;
    const struct pfvi_options* const o = &st->options;
    const double sign = copysign(1., r->dt);
    const struct pfvi_symmetric_constants* const constants = symmetric_constants(st);
    const double kappa = constants->kappa;
    const double u_target = constants->u_target;
    const double sigma0 = st->density_sigma, g0 = st->density_dlog;
    st->statistics.epsilon_effective = constants->epsilon_effective;
    if (kappa < PFVI_KAPPA_WARN && !st->kappa_warned){
        warn_small_kappa(r, st, kappa);
    }
    if (!(sigma0 > 0.)){
        return control_unpaired(r, st, N, t0, sign, constants);
    }
    symmetric_discard_implausible(st, sigma0);
    if (!symmetric_on_track(st, kappa)){
        steady_forget(st);
        st->track_mismatch = 0.;  // a fresh track starts its average afresh
        st->track_seen_lo = st->track_seen_hi = t0;
    }
    struct track_position t = symmetric_position_at(r, st, N, t0, sign, kappa, sigma0, g0);
    // An output time does not cap the step (pfvi_output.c shows it): the
    // step is the one sim.dt as the last step proposed it would give.
    const int output = st->output_uncapped;
    const double dt = (output && st->dt_proposed != 0.) ? fabs(st->dt_proposed) : fabs(r->dt);
    // (With hooks that need REBOUND's own outputs, output_cut, a sim.dt the
    // run did not propose caps: REBOUND finishes on a time by checking
    // t + sim.dt against it.)
    // A track restarted by an edit (a post-timestep hook or a heartbeat that
    // changes a mass every step) starts with the run's own proposal as its
    // first interval where that is a little shorter: REBOUND decided from it
    // whether this step finishes on a requested time, so it caps (uncapped,
    // steps passed the time and came back: a hostile trial); taken as a cap
    // of the longer interval, it left the rest, a sliver, as the next step
    // (112 steps for the unedited run's 57). Far shorter
    // (PFVI_EDIT_TRACK_NEAR), it is the rest of an interval cut at an output.
    const int own_proposal = st->dt_proposed != 0. && dt == fabs(st->dt_proposed);
    const int uncapped = !st->output_cut
        && ((symmetric_on_track(st, kappa) && (own_proposal || dt == fabs(st->dt_last_full)))
            || (st->dt_proposed == 0. && (dt == PFVI_REBOUND_DT_DEFAULT || output)));
    const double cap = uncapped ? INFINITY : dt;
    if (st->track_edited && own_proposal && cap < t.remaining && cap >= PFVI_EDIT_TRACK_NEAR*t.remaining){
        t.rho = kappa/cap;
        t.length = t.remaining = cap;
    }
    {
        // A reversal meeting a step the way out took asymmetrically takes it
        // back as it was and restores the track as that step found it, so
        // that the way back goes on as a flip there would (issue 40, item 7).
        const long due = replay_due(st, t0, sign);
        const struct pfvi_replay entry = (due >= 0) ? st->replay[(st->replay_first + (size_t)due) % PFVI_REPLAY_MAX]
            : (struct pfvi_replay){0};
        const struct pfvi_replay* e = (due >= 0) ? &entry : NULL;
        if (e && e->pin && !(fabs(t0 - e->t_end) > PFVI_REPLAY_PIN_DRIFT*fabs(e->t_end - e->t_start))){
            // A pin met on the way out's grid: nothing to resynchronise.
            replay_remove(st, (size_t)due);
            e = NULL;
        }
        // (The track may be off where the way out restarted it: the entry's
        // own kappa, if it had a track, says it is this run's.)
        if (e && (e->track_kappa == kappa || !(e->rho > 0.))){
            struct pfvi_field field_replay;
            const double back = e->t_start - t0;
            // Only REBOUND or the user cap it: not pfvi's own proposal.
            const double replay_cap = (output || (st->dt_proposed != 0. && fabs(r->dt) == fabs(st->dt_proposed)))
                ? INFINITY : fabs(r->dt);
            if (fabs(back) <= replay_cap){
                const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, back);
                if (trial == PFVI_TRIAL_ERROR){
                    return 0.;
                }
                if (trial == PFVI_TRIAL_OK && pfvi_field_of(r, st, &field_replay)){
                    double sigma1 = 0., g1 = 0.;
                    pfvi_step_density(r->particles, NULL, N, &field_replay, o->stages, st->partners, &sigma1, &g1, NULL);
                    pfvi_commit_step(r, st, N, back);
                    r->t = e->t_start;
                    replay_restore(st, e);
                    replay_remove(st, (size_t)due);
                    st->density_sigma = sigma1;
                    st->density_dlog = g1;
                    st->density_N = N;
                    st->density_stages = o->stages;
                    r->dt = sign*symmetric_position_at(r, st, N, r->t, sign, kappa, sigma1, g1).remaining;
                    st->dt_proposed = r->dt;
                    return back;
                }
                if (trial == PFVI_TRIAL_OK){
                    pfvi_roll_back(r, st, N, t0);
                }
            }
            if (e->pin){
                replay_remove(st, (size_t)due);   // (a pin not replayed: the way back goes on as without it)
            }else{
                pfvi_replay_clear(st);   // not replayed: the log no longer describes the way back
            }
        }
    }
    struct pfvi_replay before;
    before.t_start = t0;
    before.sign = sign;
    before.pin = 0;
    replay_keep(st, &before);
    st->track_edited_before = st->track_edited;
    st->track_edited = 0;
    double h = fmin(t.remaining, cap);
    // The start's partners (the last step's end's, or found at this start by
    // pfvi_step_start), before the trials' ends overwrite st->partners.
    memcpy(st->partners_start, st->partners, N*sizeof(*st->partners));
    // The state is at t0 + t_lo: a step capped to reach t0 + sign cap goes
    // sign cap - t_lo (t's rounding over the track, kept as x's and v's is).
    const double t_lo = pfvi_t_lo(r, st);
    const double lambda0 = st->density_scale;
    double lambda = lambda0;
    double sigma1 = 0., g1 = 0., u = 0.;
    int restart = 0, shortened = 0, retakes = 0, unresolved = 0, split = 0;
    struct pfvi_field field;
    for (;;){
        const int capped = (h == cap);
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, capped ? sign*h - t_lo : sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        double h_next = 0.5*h;
        if (trial == PFVI_TRIAL_OK){
            if (!pfvi_field_of(r, st, &field)){
                pfvi_roll_back(r, st, N, t0);
                return 0.;
            }
            pfvi_step_density(r->particles, NULL, N, &field, o->stages, st->partners, &sigma1, &g1, NULL);
            u = symmetric_resolution_both(r, st, N, sign*h, &field, constants->above);
            // (Both ends: a reversed step makes the same check.)
            const int jump = fmax(sigma0, sigma1)*lambda*h > PFVI_DENSITY_JUMP_MAX*kappa;
            // The error the stages imply, relative to the worst along
            // Kepler orbits (about epsilon per orbit there).
            // (Up to 1.05 the power is at most 1.05^14 < 2, below
            // RESOLUTION_MAX: no pow() for the decision it would not change.)
            const double ratio = u/u_target;
            const int coarse = ratio > 1.05 && pow(ratio, 2.*o->stages - 2.) > PFVI_RESOLUTION_MAX;
            // Still coarse after the last retake: no shorter step resolves them.
            unresolved = coarse && retakes == PFVI_RESOLUTION_RETRIES;
            // A whole interval (taken in one step, as the track began it)
            // that the density outran and whose stages show it: the density
            // at an end SPLIT_DENSITY times what the step was sized for, and
            // the forces resolved worse than SPLIT_RESOLUTION of the Kepler
            // worst (pfvi.h: a comet falling in from under a planet's term).
            // It is crossed in two halves: the same interval, so the track
            // and its grid stay as they were, and a reversal, meeting the
            // whole interval from its other end, reads the same ends and
            // stages and splits it the same way (time-symmetric, where a
            // retake is not).
            const int whole = !split && !shortened && !capped && t.done == 0. && h == t.length;
            if (!jump && !coarse && whole && ratio > PFVI_SPLIT_RESOLUTION
                    && fmax(sigma0, sigma1)*lambda*h > PFVI_SPLIT_DENSITY*kappa){
                pfvi_roll_back(r, st, N, t0);
                st->statistics.n_rejected++;
                split = 1;
                h = 0.5*t.length;
                continue;
            }
            if (!jump && (!coarse || unresolved)){
                break;
            }
            pfvi_roll_back(r, st, N, t0);
            if (jump){
                restart = 1;
            }else{
                // The step that resolves the forces as the density should
                // have: the interval starts afresh here, lambda times denser.
                retakes++;
                const double scale = fmin(1./fmin(0.5, u_target/u), PFVI_DENSITY_SCALE_MAX/lambda);
                lambda *= scale;
                t.rho *= scale;
                t.length = kappa/t.rho;
                t.done = 0.;
                t.remaining = t.length;
                h_next = fmin(t.remaining, cap);
            }
        }
        st->statistics.n_rejected++;
        if (trial == PFVI_TRIAL_NOT_CONVERGED){
            // The solve's own failure, unless its last stages show forces the
            // step does not resolve (a time scale the density missed: the
            // resolution check would retake it had the solve converged).
            // (Stages with a force that is not finite: halved for that.)
            int resolved = 1;
            if (!st->trial.stage_failed && pfvi_field_of(r, st, &field)){
                const double u_last = symmetric_resolution(r, st, N, sign*h, &field, constants->above);
                resolved = !(pow(u_last/u_target, 2.*o->stages - 2.) > PFVI_RESOLUTION_MAX);
            }
            st->statistics.n_solve_halved += (uint64_t)resolved;
        }
        shortened = 1;
        h = h_next;
        if (t0 + sign*h == t0){
            // (flag: the last trial's solve converged; the step was retaken
            // shorter for what its end showed, a closer approach)
            pfvi_give_up(st, (struct pfvi_fault){.kind = PFVI_FAULT_NOT_CONVERGED, .n = (size_t)o->stages,
                .value = st->trial.change, .rounds = st->trial.rounds, .t0 = t0,
                .flag = (trial != PFVI_TRIAL_NOT_CONVERGED)});
            return 0.;
        }
    }
    const int capped = (h == cap);
    h = capped ? sign*h - t_lo : sign*h;
    pfvi_commit_step(r, st, N, h);
    // The time the end's force was evaluated at (the trial's t0 + h), before
    // t is relabelled below (pfvi_output_forces_hold compares at it).
    const double t_force = r->t;
    if (capped){
        // The time REBOUND asked for, which the state is at (the stage
        // predictor follows the relabelling).
        st->predictor_t = (st->predictor_t == r->t) ? t0 + sign*cap : st->predictor_t;
        r->t = t0 + sign*cap;
        st->t_compensation = 0.;
    }else{
        // TwoSum: what r->t = t0 + h lost, with what t lacked before; then
        // folded into t (TwoSum again), so that t is the double nearest the
        // state's time and t_lo stays below half its last place. Left to
        // accumulate, t_lo grew by the same rounding every step of a held
        // track (constant h): 2.7e-11 yr over 1600 steps of the outer solar
        // system, shown as t off by that much (Jupiter 1e-11 off IAS15
        // where 8e-13 is the round-off floor: issue 42, item 4).
        const double t1 = r->t, back = t1 - h;
        const double lost = t_lo + ((t0 - back) + (h - (t1 - back)));
        const double folded = t1 + lost, part = folded - t1;
        st->predictor_t = (st->predictor_t == t1) ? folded : st->predictor_t;
        r->t = folded;
        st->t_compensation = (t1 - (folded - part)) + (lost - part);
    }
    st->t_compensated = r->t;
    st->end_force_t = t_force;
    st->end_force_label = r->t;
    int asymmetric = shortened;
    if (unresolved){
        // Shorter steps did not help: the density was right, keep its scale.
        count_unresolved(r, st, t0);
        t.rho *= lambda0/lambda;
        t.length = kappa/t.rho;
        t.remaining = t.length;
        lambda = lambda0;
    }
    {
        // The stages' estimate, as the error per orbit a step of this
        // resolution makes where it is worst on a Kepler orbit.
        static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
        st->statistics.error_estimate = constant[o->stages]*pow(u/resolution_constant[o->stages], 2.*o->stages - 2.);
    }
    // Where the track now stands (a capped step counts as its cap: what
    // it took beyond that was the track's own rounding).
    const double step = capped ? cap : fabs(h);
    const int full = (step == t.remaining);
    st->track_restarted = restart;
    if (restart){
        st->rho = 0.;
        steady_forget(st);
        st->track_mismatch = 0.;
        st->track_seen_lo = st->track_seen_hi = r->t;
    }else{
        st->rho = t.rho;
        st->rho_sign = sign;
        st->track_kappa = kappa;
        st->track_at_end = full;
        st->track_done = full ? t.length : t.done + step;
        // Lambda falls back where a whole interval resolved the forces
        // finer than needed (never below 1: the density's own steps).
        // (Not on a way back still retracing logged steps: the way out's
        // fallbacks are replayed where it took them, and one of its own,
        // decided on ends that differ in the last bits, would be a step the
        // way out did not take.)
        const int retracing = st->replay_count[replay_side(-sign)] > 0;
        if (full && t.done == 0. && lambda > 1. && !retracing && u*PFVI_RESOLUTION_SLACK < u_target){
            // Clamped at exactly 1: lambda*(1/lambda) can round below it, and
            // a lambda below 1 is taken for a damaged one (the track restarts).
            const double lowered = fmax(1., lambda*fmax(1./lambda, PFVI_RESOLUTION_SLACK*u/u_target));
            st->rho *= lowered/lambda;
            lambda = lowered;
            st->track_done = kappa/st->rho;
            asymmetric = 1;
        }
        const int unseen = full && symmetric_interval_unseen(st, r->t, t.length, sign);
        if (full && !shortened){
            asymmetric |= steady_update(st, N, field.G, r->t, t.length, sign, lambda*sigma1, unseen && t.done == 0.);
            st->track_done = kappa/st->rho;
        }
        if (!st->steady.hold && unseen && t.done == 0. && !shortened && sigma0 > 0. && sigma1 > 0.){
            // The interval's mismatch, averaged; a drift of the average is
            // taken out of rho (pfvi.h, PFVI_TRACK_MISMATCH_MAX).
            const double m = log(t.rho/(lambda*sqrt(sigma0)*sqrt(sigma1)));
            st->track_mismatch += PFVI_TRACK_MISMATCH_WEIGHT*(m - st->track_mismatch);
            if (fabs(st->track_mismatch) > PFVI_TRACK_MISMATCH_MAX){
                st->rho *= exp(-st->track_mismatch);
                st->track_done = kappa/st->rho;
                st->track_mismatch = 0.;
                asymmetric = 1;
            }
        }
    }
    st->density_scale = lambda;
    st->statistics.n_asymmetric += (uint64_t)asymmetric;
    // The halves of a split interval are logged beside the asymmetric steps,
    // though they are time-symmetric: the way back then takes them back as
    // they were and finds the track as the way out left it (a whole interval
    // crossed by a varying track carries the grid's round-off on, and the
    // track amplifies it: docs/solve.md; the retakes a split replaced were
    // such resynchronisations), and takes them as halves even where its own
    // checks, on ends that differ in the last bits, would not split.
    // So is the step after a restart of the track: it starts off the track,
    // where the proposal caps it, so it is never split; the way back meets
    // the same interval from its far end on a running track, takes it as
    // whole and may split it (the crossing comet a = 4, f = 0 at the
    // defaults: split at t = 177.5 on the way back only, then 9 more steps
    // of its own, 1.3e-5 AU back; logged, 9.9e-13).
    const int logged_too = st->replay_next;
    st->replay_next = split || restart;
    // A pin (PFVI_REPLAY_PIN_EVERY): a whole interval, on the way out (not
    // while a way back retraces logged steps).
    before.pin = !(asymmetric || split || logged_too) && !restart && !capped && full && t.done == 0.
        && st->replay_count[replay_side(-sign)] == 0 && (st->statistics.n_steps + 1) % PFVI_REPLAY_PIN_EVERY == 0;
    if (asymmetric || split || logged_too || before.pin){
        // (A restart of the track and the steady hold's start or end are
        // logged too: the replay restores the track as it was before them.)
        before.t_end = r->t;
        replay_push(st, &before);
    }
    // The density at the end is the next step's start density.
    st->density_sigma = sigma1;
    st->density_dlog = g1;
    st->density_N = N;
    st->density_stages = o->stages;
    // Propose exactly the next step, so that REBOUND shortens it only to
    // finish on time; the next step recomputes it the same way.
    r->dt = sign*symmetric_position_at(r, st, N, r->t, sign, kappa, sigma1, g1).remaining;
    st->dt_proposed = r->dt;
    if (!shortened && !split && t.remaining <= cap){
        st->dt_last_full = h;
    }
    return h;
}

double pfvi_controlled_step(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    if (st->options.step_control == PFVI_STEP_CONTROL_SYMMETRIC){
        return control_symmetric(r, st, N, t0);
    }
    const struct reb_particle* const p0 = st->start;
    double omega_start_max = 0.;
    for (size_t i=0; i<N; i++){
        const double v[3] = {p0[i].vx, p0[i].vy, p0[i].vz};
        pfvi_osculating_circle(v, st->end[i].a, &st->osculating_start[i]);
        omega_start_max = fmax(omega_start_max, control_omega(st, &st->osculating_start[i]));
    }
    if (st->options.step_control == PFVI_STEP_CONTROL_REVERSIBLE){
        st->retry_allowed = 1;
        const double h = control_reversible(r, st, N, t0, omega_start_max);
        st->retry_allowed = 0;
        return h;
    }
    return control_seed(r, st, N, t0, omega_start_max);
}

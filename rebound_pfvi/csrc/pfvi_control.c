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
        rejections++;
        const double h_next = h*shrink;
        if (rejections >= PFVI_CONTROL_MAX_REJECTIONS || t0 + h_next == t0){
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_REJECTED, .t0 = t0, .h = h,
                .value = (trial == PFVI_TRIAL_OK) ? view.error : NAN};
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
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_UNSOLVED, .t0 = t0, .rounds = (uint64_t)trials,
            .h = sign*h, .value = F};
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

// kappa = (epsilon/C_s)^(1/(2s - 2)): the step in units of 1/sigma.
static double symmetric_kappa(const struct pfvi_options* o){
    static const double constant[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_CONSTANTS;
    const double kappa = pow(o->epsilon/constant[o->stages], 1./(2.*o->stages - 2.));
    return fmin(kappa, PFVI_KAPPA_MAX);
}

// gamma_s of the eccentricity factor: the error per orbit at fixed kappa grows
// like (1 - e)^(-beta_s); (1 - e^2)^(-beta_s/(2s - 2)) in sigma evens it out.
static double symmetric_gamma(const struct pfvi_options* o){
    static const double beta[PFVI_STAGES_MAX + 1] = PFVI_SYMMETRIC_BETA;
    return beta[o->stages]/(2.*o->stages - 2.);
}

// The symmetric step (Hairer & Soderlind 2005, SIAM J. Sci. Comput. 26,
// 1838): h_n = kappa/rho_n+1/2 with
//     rho_n+1/2 = rho_n-1/2 + kappa G(y_n),   G = d log(sigma)/dt,
// an explicit update that is the same read forward or backward, so that rho
// tracks the density sigma of pfvi_density along the orbit and the sequence
// of steps reverses exactly. One stage solve per step; a solve that does not
// converge is retried at half the step (counted in n_rejected and
// n_asymmetric), as is a step at whose end the density exceeds
// PFVI_DENSITY_JUMP_MAX/h (kappa/h is the density it was sized for): along a
// Kepler orbit sigma/rho stays within 0.76-1.35 (e = 0.9, the largest
// steps), but a close approach of a third body raises the density within
// one step by 10^3 in Burrau's problem. Without pairs (no gravity, or no
// massive body) the steps are sim.dt.
//
// sim.dt is the step proposed after each step. If it is still that (or only
// its sign was flipped: REBOUND integrating back to a time it overshot, or
// the user reversing), the step is kappa/rho; if it was changed (REBOUND
// shortening the last step to finish on time, or the user), it caps the
// step, and a capped step ends the track: rho starts afresh from sigma at
// the next step, since it no longer belongs to the state it arrives at.
// rho for a step in direction `sign` from a state of density sigma and rate
// g, after a last step taken with rho_last in direction sign_last (rho_last
// = 0: none): the track continued, a reversal retracing that step, or a
// fresh start from sigma. The step's start and the proposal at the end of
// the last step both use it, so that they agree.
static double symmetric_rho(double rho_last, double sign_last, double sign, double kappa, double sigma, double g){
    double rho = 0.;
    if (rho_last > 0.){
        rho = (sign_last == sign) ? rho_last + sign*kappa*g : rho_last;
    }
    if (!(rho > 0.) || !isfinite(rho)){
        rho = sigma + 0.5*sign*kappa*g;
        rho = (rho > 0.) ? rho : sigma;
    }
    return rho;
}

static double control_symmetric(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    const double sign = copysign(1., r->dt);
    const int proposed = (st->rho > 0. && fabs(r->dt) == fabs(st->dt_proposed));
    const double cap = proposed ? INFINITY : fabs(r->dt);
    const double kappa = symmetric_kappa(&st->options);
    double sigma, g;
    const double gamma = symmetric_gamma(&st->options);
    const int paired = pfvi_density(st->start, st->end, st->centre, N, gamma, &sigma, &g);
    const double rho = paired ? symmetric_rho(st->rho, st->rho_sign, sign, kappa, sigma, g) : 0.;
    double h = paired ? fmin(kappa/rho, cap) : fabs(r->dt);  // without pairs: sim.dt
    double sigma1 = 0., g1 = 0.;
    for (;;){
        const enum pfvi_trial trial = pfvi_trial_step(r, st, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        if (trial == PFVI_TRIAL_OK){
            // The density where the step ended: a step that ran into a much
            // denser region (a close approach the track could not foresee,
            // as in Burrau's problem) is retried shorter.
            if (!paired){
                break;
            }
            pfvi_density(r->particles, NULL, st->centre, N, gamma, &sigma1, &g1);
            if (!(sigma1*h > PFVI_DENSITY_JUMP_MAX*kappa)){
                break;
            }
            pfvi_roll_back(r, st, N, t0);
        }
        st->statistics.n_rejected++;
        st->statistics.n_asymmetric++;
        h *= 0.5;
        if (t0 + sign*h == t0){
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_NOT_CONVERGED, .n = (size_t)st->options.stages,
                .value = st->trial.change, .rounds = st->trial.rounds, .t0 = t0};
            return 0.;
        }
    }
    h *= sign;
    pfvi_commit_step(r, st, N, h);
    st->statistics.error_estimate = 0.;
    // A step shorter than kappa/rho (capped or halved) ends the track.
    st->rho = (paired && fabs(h) == kappa/rho) ? rho : 0.;
    st->rho_sign = sign;
    if (paired){
        // Propose exactly the next step, so that REBOUND shortens it only to
        // finish on time; the next step's start recomputes it the same way.
        r->dt = sign*kappa/symmetric_rho(st->rho, sign, sign, kappa, sigma1, g1);
        st->dt_proposed = r->dt;
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

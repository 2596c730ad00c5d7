/**
 * pfvi_control.c: adaptive steps from osculating circles (seed section 4).
 *
 * At each end of a step, every particle's path has an osculating circle:
 * radius R = |v|^3 / |v x a| and centre O = x + |v|^2 (v x a) x v / |v x a|^2.
 * The seed bounds the step's position error by | |R1 - R2| - |O1 - O2| |: if
 * the curvature changes monotonically the two circles are nested, the centre
 * moves along the evolute by less than the radius changes, and the estimate
 * measures how far the path is from the circle the fitted interpolation
 * follows. It is used relative to min(R1, R2), for the particle where it is
 * largest, and is symmetric in the two ends and unchanged when velocities
 * are reversed.
 *
 * The seed's paths are planar. On a space curve the centre also moves out of
 * the circle's plane, at R tau per unit length (tau the torsion: dO/ds =
 * R' N + R tau B), a first-order term that is geometry, not integration
 * error; near a straight stretch perturbed out of its plane (a comet passing
 * Jupiter) it made the estimate first order in h and the steps collapse
 * (1e-7 yr at epsilon 1e-9). So the centre's motion is measured in the plane
 * normal to the mean binormal of the two ends, which removes that term to
 * third order and leaves planar motion untouched bit for bit.
 *
 * Two controllers use it:
 *  - "seed": accept the step if the estimate is at most epsilon, else retry it
 *    shorter; propose the next step by the standard rule
 *    h 0.9 (epsilon/estimate)^(1/3), bounded in growth and shrink.
 *  - "reversible": solve estimate(y_n, y_n+1(h)) = epsilon for h (secant on
 *    log h), with every particle fitted to the mean of its curvature
 *    frequencies at the two ends. Both conditions are symmetric in y_n and
 *    y_n+1, so the step taken backward from y_n+1 is the same step: the
 *    time-symmetric step selection of Hut, Makino & McMillan (1995, ApJ 443,
 *    L93), here with the seed's estimate as the step function.
 * Both keep u = omega h <= u_max with the curvature frequency (or the fixed
 * omega), whatever the fitting, and propose the next step through r->dt, so
 * that REBOUND's exact_finish_time can shorten it as it does for IAS15.
 */
#include <float.h>
#include <math.h>
#include "pfvi.h"

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
static int pfvi_osculating_comparable(const struct pfvi_osculating* c0, const struct pfvi_osculating* c1){
    if (!c0->defined || !c1->defined){
        return 0;
    }
    return c0->binormal[0]*c1->binormal[0] + c0->binormal[1]*c1->binormal[1]
        + c0->binormal[2]*c1->binormal[2] >= 0.;
}

double pfvi_osculating_error(const struct reb_particle* p0, const struct pfvi_osculating* c0,
        const struct reb_particle* p1, const struct pfvi_osculating* c1, double* noise_out){
    *noise_out = 0.;
    if (!c0->defined || !c1->defined){
        return 0.;
    }
    // O1 - O0 as the step's displacement plus the change of the offsets, so
    // that the positions' size enters only through one rounding.
    double d[3] = {
        (p1->x - p0->x) + (c1->offset[0] - c0->offset[0]),
        (p1->y - p0->y) + (c1->offset[1] - c0->offset[1]),
        (p1->z - p0->z) + (c1->offset[2] - c0->offset[2])};
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
    const double size = fmax(fmax(fabs(p0->x), fabs(p1->x)), fmax(fmax(fabs(p0->y), fabs(p1->y)),
                fmax(fabs(p0->z), fabs(p1->z))));
    const double noise = 8.*DBL_EPSILON*(size + r_max)/r_min;
    *noise_out = noise;
    return (estimate > noise) ? estimate - noise : 0.;
}

// The frequency of the controller's u bound: the fixed omega, or the curvature one.
static double control_omega(const struct pfvi_state* s, const struct pfvi_osculating* c){
    return (s->frequency == PFVI_FREQUENCY_FIXED) ? s->omega : c->omega;
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

static struct control_view control_look(const struct reb_simulation* r, struct pfvi_state* s, size_t N){
    const struct reb_particle* const ps = r->particles;
    struct control_view view = {0., 0., 0, 0., 0.};
    for (size_t i=0; i<N; i++){
        const double v[3] = {ps[i].vx, ps[i].vy, ps[i].vz};
        const double a[3] = {ps[i].ax, ps[i].ay, ps[i].az};
        struct pfvi_osculating c1;
        pfvi_osculating_circle(v, a, &c1);
        const struct pfvi_osculating* const c0 = &s->osculating_start[i];
        const int comparable = pfvi_osculating_comparable(c0, &c1);
        view.informed |= comparable;
        double noise = 0.;
        const double error = comparable ? pfvi_osculating_error(&s->start[i], c0, &ps[i], &c1, &noise) : 0.;
        if (error > view.error){
            view.error = error;
            view.noise = noise;
        }
        s->omega_end[i] = c1.omega;
        const double w1 = control_omega(s, &c1);
        view.omega_end_max = fmax(view.omega_end_max, w1);
        view.omega_mean_max = fmax(view.omega_mean_max, 0.5*(control_omega(s, c0) + w1));
    }
    if (s->frequency == PFVI_FREQUENCY_FIXED && s->omega > 0.){
        view.informed = 1;
    }
    return view;
}

static void control_error_giving_up(struct reb_simulation* r, const struct pfvi_state* s, double t0,
        double h, double error){
    pfvi_error(r, "pfvi: no step from t = %.17g meets epsilon = %g (estimate %.3g at dt = %.3g after %d "
            "tries); step not taken, state restored. Raise epsilon or check the forces.",
            t0, s->epsilon, error, h, PFVI_CONTROL_MAX_REJECTIONS);
}

// |h| at most u_max / omega, sign kept.
static double control_u_bound(const struct pfvi_state* s, double h, double omega){
    if (omega > 0. && fabs(h)*omega > s->u_max){
        return copysign(s->u_max/omega, h);
    }
    return h;
}

static double control_seed(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double omega_start_max){
    double h = control_u_bound(s, r->dt, omega_start_max);
    int rejections = 0;
    struct control_view view = {0., 0., 0, 0., 0.};
    for (;;){
        const enum pfvi_trial trial = pfvi_trial_step(r, s, N, t0, h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        double shrink = 0.5;  // a stage solve that did not converge: halve the step
        if (trial == PFVI_TRIAL_OK){
            view = control_look(r, s, N);
            if (view.error <= s->epsilon){
                break;
            }
            pfvi_roll_back(r, s, N, t0);
            shrink = fmax(PFVI_CONTROL_SHRINK_MIN, PFVI_CONTROL_SAFETY*pow(s->epsilon/view.error, 1./PFVI_CONTROL_ORDER));
        }
        s->n_rejected++;
        rejections++;
        const double h_next = h*shrink;
        if (rejections >= PFVI_CONTROL_MAX_REJECTIONS || t0 + h_next == t0){
            control_error_giving_up(r, s, t0, h, (trial == PFVI_TRIAL_OK) ? view.error : NAN);
            return 0.;
        }
        h = h_next;
    }
    pfvi_commit_step(r, s, N, h);
    s->error_estimate = view.error;
    double grow = 1.;  // no particle on a curve: nothing to go on, keep the step
    if (view.informed){
        grow = (view.error > 0.) ? PFVI_CONTROL_SAFETY*pow(s->epsilon/view.error, 1./PFVI_CONTROL_ORDER)
                                 : PFVI_CONTROL_GROW_MAX;
        grow = fmin(PFVI_CONTROL_GROW_MAX, fmax(PFVI_CONTROL_SHRINK_MIN, grow));
        if (rejections){
            grow = fmin(grow, 1.);
        }
    }
    r->dt = control_u_bound(s, h*grow, view.omega_end_max);
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
static double control_reversible(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double omega_start_max){
    const double cap = fabs(r->dt), sign = copysign(1., r->dt);
    double h = cap;
    if (s->dt_reversible != 0. && copysign(1., s->dt_reversible) == sign && fabs(s->dt_reversible) < cap){
        h = fabs(s->dt_reversible);
    }
    h = fabs(control_u_bound(s, h, omega_start_max));
    const int fitted = (s->fitting != PFVI_FITTING_NONE && s->frequency == PFVI_FREQUENCY_CURVATURE);
    double lo = 0., hi = INFINITY;                // F(lo) < 1 < F(hi) once bracketed
    double log_h_prev = NAN, log_F_prev = NAN;    // the previous trial, for the secant
    struct control_view view = {0., 0., 0, 0., 0.};
    double F = NAN;
    int solved = 0, trials = 0;
    while (trials < PFVI_REVERSIBLE_MAX_TRIALS){
        const enum pfvi_trial trial = pfvi_trial_step(r, s, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        if (trial == PFVI_TRIAL_NOT_CONVERGED){
            s->n_rejected++;
            hi = h;
            log_h_prev = NAN;
            h *= 0.5;
            if (t0 + sign*h == t0){
                break;
            }
            continue;  // not counted as a trial of the step equation
        }
        trials++;
        view = control_look(r, s, N);
        const double error_ratio = view.error/s->epsilon;
        const double u_ratio = h*view.omega_mean_max/s->u_max;
        F = fmax(error_ratio, u_ratio);
        // The frequencies this h asks for, and how far they are from those used.
        double change = 0., omega_scale = 0.;
        if (fitted){
            for (size_t i=0; i<N; i++){
                const double mean = 0.5*(s->osculating_start[i].omega + s->omega_end[i]);
                change = fmax(change, fabs(mean - s->omega_fit[i]));
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
        pfvi_roll_back(r, s, N, t0);
        if (fitted){
            for (size_t i=0; i<N; i++){
                s->omega_fit[i] = 0.5*(s->osculating_start[i].omega + s->omega_end[i]);
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
        const enum pfvi_trial trial = pfvi_trial_step(r, s, N, t0, sign*h);
        if (trial == PFVI_TRIAL_ERROR){
            return 0.;
        }
        if (trial == PFVI_TRIAL_OK){
            view = control_look(r, s, N);
            solved = 1;
            s->n_asymmetric++;
        }
    }
    if (!solved){
        pfvi_error(r, "pfvi: the reversible step equation from t = %.17g was not solved in %d trial steps "
                "(last dt = %.6g, estimate/epsilon = %.3g); step not taken, state restored. Try "
                "step_control = 'seed' or a larger epsilon.", t0, trials, sign*h, F);
        return 0.;
    }
    h *= sign;
    pfvi_commit_step(r, s, N, h);
    s->error_estimate = view.error;
    s->dt_reversible = h;
    // The next cap: room to grow, as in the seed controller.
    r->dt = view.informed ? PFVI_CONTROL_GROW_MAX*h : h;
    return h;
}

double pfvi_controlled_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0){
    const struct reb_particle* const p0 = s->start;
    double omega_start_max = 0.;
    for (size_t i=0; i<N; i++){
        const double v[3] = {p0[i].vx, p0[i].vy, p0[i].vz};
        pfvi_osculating_circle(v, s->end[i].a, &s->osculating_start[i]);
        omega_start_max = fmax(omega_start_max, control_omega(s, &s->osculating_start[i]));
    }
    if (s->step_control == PFVI_STEP_CONTROL_REVERSIBLE){
        return control_reversible(r, s, N, t0, omega_start_max);
    }
    return control_seed(r, s, N, t0, omega_start_max);
}

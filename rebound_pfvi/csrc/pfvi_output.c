/**
 * pfvi_output.c: outputs that leave the run's steps as they are (issue 36).
 *
 * REBOUND users record a run as `for t in times: sim.integrate(t)`; with
 * exact_finish_time = 1 (REBOUND's default) each time caps a step, and a
 * capped step breaks the symmetric control's time-symmetric track. Instead,
 * where the control allows it (pfvi_output_eligible), the step takes its
 * whole interval and the simulation is given the state at the requested
 * time from an *output step*: one trial step of the same scheme from the
 * step's end back to that time, never committed. The run's own state (the
 * step's end) is kept in output_real, and the next step takes it up again
 * if the simulation still shows the output unedited. So the steps of a run,
 * and with them every state it computes, do not depend on its output times;
 * an output's error is the run's at the step's end plus one step shorter
 * than the run's own. An edit, an added or removed particle, a changed t,
 * stages, epsilon or force model makes the shown state the user's, from
 * which the run goes on as after any edit.
 */
#include <math.h>
#include <string.h>
#include "pfvi.h"
#include "boundary.h"

static void output_keep(const struct reb_particle* ps, struct pfvi_output_particle* out, size_t N){
    for (size_t i=0; i<N; i++){
        memcpy(out[i].xv, &ps[i].x, sizeof(out[i].xv));
        out[i].m = ps[i].m;
        out[i].a[0] = ps[i].ax; out[i].a[1] = ps[i].ay; out[i].a[2] = ps[i].az;
    }
}

static void output_put(struct reb_particle* ps, const struct pfvi_output_particle* in, size_t N){
    for (size_t i=0; i<N; i++){
        memcpy(&ps[i].x, in[i].xv, sizeof(in[i].xv));
        ps[i].m = in[i].m;
    }
}

// Bit for bit, as pfvi_state_is_end compares (0 and -0 differ).
static int output_same(const struct reb_particle* ps, const struct pfvi_output_particle* shown, size_t N){
    for (size_t i=0; i<N; i++){
        if (memcmp(&ps[i].x, shown[i].xv, sizeof(shown[i].xv)) != 0 || memcmp(&ps[i].m, &shown[i].m, sizeof(double)) != 0){
            return 0;
        }
    }
    return 1;
}

// The variational particles of configuration k: as shown, or all scaled by
// one factor c (REBOUND rescales a configuration past 1e100 after a step,
// the output's; the tangent map is linear, so the run's are scaled by c).
// 0 if edited otherwise.
static int output_var_scale(const struct reb_simulation* r, const struct pfvi_state* st, size_t k, double* c){
    const struct reb_variational_configuration* const vc = &r->var_config[k];
    const size_t first = (size_t)vc->index, n = (vc->testparticle < 0) ? r->N : 1;
    if (first + n > st->output_var_N){
        return 0;
    }
    const struct reb_particle* const pv = r->particles_var + first;
    const struct pfvi_output_particle* const shown = st->output_var_shown + first;
    if (output_same(pv, shown, n)){
        *c = 1.;
        return 1;
    }
    double largest = 0., scale = 0.;
    for (size_t i=0; i<n; i++){
        const double* const x = &pv[i].x;
        for (int m=0; m<6; m++){
            if (fabs(shown[i].xv[m]) > largest){
                largest = fabs(shown[i].xv[m]);
                scale = x[m]/shown[i].xv[m];
            }
        }
        if (memcmp(&pv[i].m, &shown[i].m, sizeof(double)) != 0){
            return 0;
        }
    }
    if (!(scale > 0.) || !isfinite(scale)){
        return 0;
    }
    for (size_t i=0; i<n; i++){
        const double* const x = &pv[i].x;
        for (int m=0; m<6; m++){
            if (!(fabs(x[m] - scale*shown[i].xv[m]) <= PFVI_OUTPUT_RESCALE_SLACK*fabs(scale)*largest)){
                return 0;
            }
        }
    }
    *c = scale;
    return 1;
}

// REBOUND's periodic wrap (reb_boundary_check, after every step), applied
// by pfvi to states REBOUND does not see when it would: the output before
// REBOUND's own pass (which then finds nothing to do, so that the output is
// recognised as shown), and the run's own end kept behind it when the run
// goes on from there (glue_start: a single call wraps it after the run's
// step). The run's end (st->end) keeps the state before the wrap, so that
// the next step starts from the wrapped state as after a single call's wrap
// (an edit of the particles moved). (Open boxes: pfvi_output_removed. The
// shear boundary's wrap also shifts a velocity: not mirrored.)
int pfvi_output_boundary(struct reb_simulation* r){
    if (r->boundary != REB_BOUNDARY_PERIODIC){
        return 0;
    }
    int moved = 0;
    for (size_t i=0; i<r->N && !moved; i++){
        moved = !reb_boundary_particle_is_in_box(r, r->particles[i]);
    }
    if (moved){
        reb_boundary_check(r);
    }
    return moved;
}

// An open box: REBOUND removes a body that left it after every step, from
// the state shown. Behind an output that would be the output, where the
// body may still be inside, while a single call removes it from the run's
// end: so pfvi removes it there, with REBOUND's own check, before the output
// is drawn (the body is then gone from the output too). Not with
// variational particles, whose removal REBOUND refuses.
int pfvi_output_removed(struct reb_simulation* r){
    if (r->boundary != REB_BOUNDARY_OPEN || r->N_var != 0){
        return 0;
    }
    const size_t before = r->N;
    reb_boundary_check(r);
    return r->N != before;
}

int pfvi_output_unwrap(struct reb_simulation* r, struct pfvi_state* st){
    const size_t N = r->N;
    if (r->boundary != REB_BOUNDARY_PERIODIC || N == 0 || st->end_N != N || st->N_allocated < N
            || pfvi_state_is_end(r, st)){
        return 0;
    }
    // The wrap of the end's positions, drawn in scratch (st->start: free
    // between steps) by REBOUND's own rule.
    struct reb_particle* const shown = r->particles;
    struct reb_particle* const w = st->start;
    memcpy(w, shown, N*sizeof(*w));
    for (size_t i=0; i<N; i++){
        memcpy(&w[i].x, st->end[i].xv, 3*sizeof(double));
    }
    r->particles = w;
    const int moved = pfvi_output_boundary(r);
    r->particles = shown;
    if (!moved){
        return 0;
    }
    for (size_t i=0; i<N; i++){
        if (memcmp(&w[i].x, &shown[i].x, 3*sizeof(double)) != 0){
            return 0;
        }
    }
    for (size_t i=0; i<N; i++){
        memcpy(&shown[i].x, st->end[i].xv, 3*sizeof(double));
    }
    if (pfvi_state_is_end(r, st)){
        return 1;
    }
    for (size_t i=0; i<N; i++){
        memcpy(&shown[i].x, &w[i].x, 3*sizeof(double));
    }
    return 0;
}

// Hooks REBOUND runs around each step that an output step cannot keep
// consistent with the state it shows: the ODEs of sim.create_ode (REBOUND
// integrates them over [t - dt_last_done, t] after the step, with the
// particles as the step leaves them; pfvi does not step them, so it cannot
// give them a state at an output inside its step), and pre- and post-timestep
// modifications (REBOUNDx operators among them): they act on the state
// shown, for dt_last_done, and an output step's time is not a time the run
// lived. With any of them set, outputs are REBOUND's own: the step is cut to
// end on the requested time, and every hook sees a state the run has, after
// exactly the time it lived.
int pfvi_output_hooks_kept(const struct reb_simulation* r){
    return r->N_odes == 0 && r->pre_timestep_modifications == NULL && r->post_timestep_modifications == NULL;
}

int pfvi_output_eligible(const struct reb_simulation* r, const struct pfvi_state* st){
    const struct pfvi_options* const o = &st->settings;
    return o->step_control == PFVI_STEP_CONTROL_SYMMETRIC && o->epsilon > 0. && o->fitting == PFVI_FITTING_NONE
        && r->N > 0 && pfvi_output_hooks_kept(r);
}

int pfvi_output_is_shown(const struct reb_simulation* r, const struct pfvi_state* st){
    const size_t N = r->N;
    if (st->output_N == 0 || st->output_N != N || st->N_allocated < N || r->t != st->output_t
            || st->settings.stages != st->output_stages || st->settings.epsilon != st->output_epsilon
            || !pfvi_force_model_kept(r, st)){
        return 0;
    }
    if (r->N_var != st->output_var_N || (st->output_var_N && st->var_allocated < st->output_var_N)){
        return 0;
    }
    if (!output_same(r->particles, st->output_shown, N)){
        return 0;
    }
    // A contact search set since (a radius, exit_min_distance, collisions
    // on): the run's step past the output was not searched for it. (An
    // archive written before these were kept has none: taken as edited.)
    if (st->output_check_N != N
            || memcmp(&r->exit_min_distance, &st->output_exit_min_distance, sizeof(double)) != 0
            || (int)r->collision != st->output_collision){
        return 0;
    }
    for (size_t i=0; i<N; i++){
        if (memcmp(&r->particles[i].r, &st->output_check[i].radius, sizeof(double)) != 0){
            return 0;
        }
    }
    for (size_t k=0; k<r->N_var_config; k++){
        double c;
        if (!output_var_scale(r, st, k, &c)){
            return 0;
        }
    }
    return 1;
}

void pfvi_output_take_up(struct reb_simulation* r, struct pfvi_state* st){
    const size_t N = st->output_N;
    output_put(r->particles, st->output_real, N);
    r->t = st->output_t_real;
    // The run goes on as if never interrupted: its next step starts from
    // the force its last step ended with (kept in archives with the state),
    // as within one integrate() call.
    struct pfvi_end_state* const e = st->end;
    for (size_t i=0; i<N; i++){
        memcpy(e[i].xv, st->output_real[i].xv, sizeof(e[i].xv));
        e[i].m = st->output_real[i].m;
        memcpy(e[i].a, st->output_real[i].a, sizeof(e[i].a));
        r->particles[i].ax = e[i].a[0]; r->particles[i].ay = e[i].a[1]; r->particles[i].az = e[i].a[2];
    }
    pfvi_keep_end_model(r, st, N);
    const size_t n = st->output_var_N;
    int rescaled = 0;
    for (size_t k=0; k<r->N_var_config; k++){
        double c = 1.;
        output_var_scale(r, st, k, &c);
        const struct reb_variational_configuration* const vc = &r->var_config[k];
        const size_t first = (size_t)vc->index, count = (vc->testparticle < 0) ? r->N : 1;
        rescaled |= (c != 1.);
        for (size_t v=first; v<first + count; v++){
            struct reb_particle* const p = &r->particles_var[v];
            const struct pfvi_output_particle* const q = &st->output_var_real[v];
            double* const x = &p->x;
            for (int m=0; m<6; m++){
                x[m] = (c == 1.) ? q->xv[m] : c*q->xv[m];
            }
            p->m = q->m;
            p->ax = (c == 1.) ? q->a[0] : c*q->a[0];
            p->ay = (c == 1.) ? q->a[1] : c*q->a[1];
            p->az = (c == 1.) ? q->a[2] : c*q->a[2];
            memcpy(st->var_end[v].xv, &p->x, sizeof(st->var_end[v].xv));
            st->var_end[v].m = p->m;
            st->var_end[v].a[0] = p->ax; st->var_end[v].a[1] = p->ay; st->var_end[v].a[2] = p->az;
        }
    }
    // Rescaled: their stages no longer predict the next step's (as after
    // REBOUND's rescaling without outputs, pfvi_step_start).
    st->var_end_N = rescaled ? 0 : n;
    if (rescaled){
        st->var_predictor_N = 0;
    }
    if (n && r->calculate_megno){
        r->megno_Ys = st->output_megno[0][0];
        r->megno_Yss = st->output_megno[0][1];
    }
    st->output_taken_up = !r->force_is_velocity_dependent && !r->heartbeat;
}

int pfvi_output_forces_hold(struct reb_simulation* r, struct pfvi_state* st){
    if (!pfvi_forces_run_user_code(r)){
        return 1;
    }
    const size_t N = st->output_N;
    const double t_shown = r->t;
    // (A refused evaluation rolls back to st->start: the shown state.)
    memcpy(st->start, r->particles, N*sizeof(struct reb_particle));
    output_put(r->particles, st->output_real, N);
    const int seen = r->force_is_velocity_dependent;
    // Compared with the run's end force, evaluated where the run's step
    // evaluated it: at t0 + h, which the relabelling of t (its rounding
    // folded in) may have moved by an ulp. (At the relabelled t a force
    // that reads t differed in its last bits, the run was taken as edited
    // at such outputs, and 1000 outputs took 290 steps against one call's
    // 262; a hostile trial.)
    const int at_force_t = !seen && st->output_t_real == st->end_force_label;
    r->t = at_force_t ? st->end_force_t : st->output_t_real;
    if (!pfvi_update_acceleration(r, st, N, t_shown)){
        return -1;
    }
    const struct reb_particle* const ps = r->particles;
    int same = 1;
    for (size_t i=0; i<N; i++){
        const double a[3] = {ps[i].ax, ps[i].ay, ps[i].az};
        same &= (memcmp(a, seen ? st->output_check[i].a_seen : st->output_real[i].a, sizeof(a)) == 0);
    }
    pfvi_output_show_again(r, st);
    return same;
}

void pfvi_output_show_again(struct reb_simulation* r, struct pfvi_state* st){
    output_put(r->particles, st->output_shown, st->output_N);
    output_put(r->particles_var, st->output_var_shown, st->output_var_N);
    if (st->output_var_N && r->calculate_megno){
        r->megno_Ys = st->output_megno[1][0];
        r->megno_Yss = st->output_megno[1][1];
    }
    r->t = st->output_t;
}

enum pfvi_trial pfvi_output_present(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t_out,
        int as_is){
    const double t_real = r->t;
    // The trial starts from (and a refused one rolls back to) the run's state.
    memcpy(st->start, r->particles, N*sizeof(struct reb_particle));
    output_keep(r->particles, st->output_real, N);
    for (size_t i=0; i<N; i++){
        memcpy(st->output_real[i].a, st->end[i].a, sizeof(st->end[i].a));  // the force the next step starts from
    }
    // The variational particles are stepped by the same trial (their tangent map).
    const size_t n = st->var_N;
    if (n){
        memcpy(st->var_start, r->particles_var, n*sizeof(struct reb_particle));
        output_keep(r->particles_var, st->output_var_real, n);
        for (size_t v=0; v<n; v++){
            memcpy(st->output_var_real[v].a, st->var_end[v].a, sizeof(st->var_end[v].a));
        }
    }
    if (pfvi_forces_run_user_code(r) && r->force_is_velocity_dependent){
        // What pfvi_output_forces_hold compares with at the next call: the
        // forces at the run's state now (then everything is put back).
        if (!pfvi_update_acceleration(r, st, N, t_real)){
            return PFVI_TRIAL_ERROR;   // rolled back to the run's state
        }
        for (size_t i=0; i<N; i++){
            const struct reb_particle* const p = &r->particles[i];
            st->output_check[i].a_seen[0] = p->ax; st->output_check[i].a_seen[1] = p->ay;
            st->output_check[i].a_seen[2] = p->az;
        }
        memcpy(r->particles, st->start, N*sizeof(struct reb_particle));
        if (n){
            memcpy(r->particles_var, st->var_start, n*sizeof(struct reb_particle));
        }
    }
    const uint64_t attempts = st->statistics.n_attempts;
    // The state is at t_real + t_lo (pfvi_control.c keeps t's rounding):
    // the output step goes what is left to t_out.
    const double t_lo = pfvi_t_lo(r, st);
    const enum pfvi_trial trial = as_is ? PFVI_TRIAL_OK : pfvi_trial_step(r, st, N, t_real, (t_out - t_real) - t_lo);
    st->statistics.n_attempts = attempts;  // an output is not a step of the run
    st->retry_valid = 0;  // its stages seed no step of the run
    if (trial != PFVI_TRIAL_OK){
        return trial;  // the run's state is in the simulation (the caller says what is shown)
    }
    pfvi_output_boundary(r);
    output_keep(r->particles, st->output_shown, N);
    output_keep(r->particles_var, st->output_var_shown, n);
    for (size_t i=0; i<N; i++){
        st->output_check[i].radius = r->particles[i].r;
    }
    st->output_check_N = N;
    st->output_exit_min_distance = r->exit_min_distance;
    st->output_collision = (int)r->collision;
    if (n && r->calculate_megno){
        // MEGNO's sums at the shown time: the run's, and the output step's
        // share, its integral by parts over its stages (as a step adds it;
        // <Y>'s samples, and with them the Lyapunov exponent, are the run's).
        st->output_megno[0][0] = r->megno_Ys;
        st->output_megno[0][1] = r->megno_Yss;
        r->megno_Ys += st->trial.megno_dY;
        r->megno_Yss += st->trial.megno_Y_integral;
        st->output_megno[1][0] = r->megno_Ys;
        st->output_megno[1][1] = r->megno_Yss;
    }
    r->t = t_out;
    st->output_N = N;
    st->output_var_N = n;
    st->output_t = t_out;
    st->output_t_real = t_real;
    st->output_stages = st->options.stages;
    st->output_epsilon = st->options.epsilon;
    pfvi_output_keep_model(r, st);
    st->statistics.n_outputs++;
    st->statistics.n_variational_evaluations += st->trial.variational_evaluations;
    return PFVI_TRIAL_OK;
}

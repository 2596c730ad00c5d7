/**
 * pfvi_two_point.c: the two-point scheme (stages = 2; K&V section 3), an
 * explicit step with the closed form of pfvi_fitting.c: kick with the
 * residual force a + omega^2 d (d = q - c, c the particle's centre,
 * pfvi_centre.c), rotate with the harmonic flow at omega about c, kick
 * again with the force at the end (the only force evaluation: the start
 * force is the last step's end force, pfvi_state.c). With forces that depend
 * on velocities the final kick is implicit, solved by fixed-point iteration.
 */
#include <math.h>
#include "pfvi.h"

static int two_point_prepare(struct pfvi_state* st, double h){
    (void)st; (void)h;
    return 1;
}

static enum pfvi_fit_status two_point_fit(struct pfvi_state* st, size_t i, double omega, double h){
    return pfvi_two_point_fit(omega, h, st->options.u_max, st->options.fitting == PFVI_FITTING_PHASE_LITERAL,
            &st->fit[i]);
}

static void two_point_copy_fit(struct pfvi_state* st, size_t i, size_t from){
    st->fit[i] = st->fit[from];
}

static double two_point_fitted_omega(const struct pfvi_state* st, size_t i){
    return st->fit[i].omega;
}

// The position of particle i relative to its centre at the end of a step of h.
static void end_offset(const struct pfvi_state* st, const struct reb_particle* p, size_t i, double h, double d[3]){
    const struct pfvi_centre* const c = &st->centre[i];
    d[0] = (p->x - c->x[0]) - pfvi_centre_shift(c, h, 0);
    d[1] = (p->y - c->x[1]) - pfvi_centre_shift(c, h, 1);
    d[2] = (p->z - c->x[2]) - pfvi_centre_shift(c, h, 2);
}

// Implicit final kick for velocity-dependent forces: v = vr + k (a(q, v) - ac + omega^2 d),
// by fixed-point iteration under the common stopping rule.
static int final_kick_velocity_dependent(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h){
    struct reb_particle* const ps = r->particles;
    const struct pfvi_two_point_fit* const fit = st->fit;
    double previous = INFINITY;
    for (int iteration=0; iteration<PFVI_ITERATION_MAX; iteration++){
        double change = 0., scale = 0.;
        for (size_t i=0; i<N; i++){
            const double w2 = fit[i].omega*fit[i].omega;
            const double k = fit[i].half_kick;
            double d[3];
            end_offset(st, &ps[i], i, h, d);
            const double* const ac = st->centre[i].acc;
            const double vx = st->v_rotated[i].x + k*((ps[i].ax - ac[0]) + w2*d[0]);
            const double vy = st->v_rotated[i].y + k*((ps[i].ay - ac[1]) + w2*d[1]);
            const double vz = st->v_rotated[i].z + k*((ps[i].az - ac[2]) + w2*d[2]);
            change = fmax(change, fmax(fabs(vx - ps[i].vx), fmax(fabs(vy - ps[i].vy), fabs(vz - ps[i].vz))));
            scale = fmax(scale, fmax(fabs(vx), fmax(fabs(vy), fabs(vz))));
            ps[i].vx = vx; ps[i].vy = vy; ps[i].vz = vz;
        }
        const double relative = (scale > 0.) ? change/scale : change;
        const enum pfvi_iteration verdict = pfvi_iteration_verdict(relative, previous,
                iteration == PFVI_ITERATION_MAX - 1);
        if (verdict == PFVI_CONVERGED){
            return 1;
        }
        if (verdict == PFVI_FAILED){
            break;
        }
        previous = relative;
        if (!pfvi_update_acceleration(r, st, N, t0)){
            return 0;
        }
    }
    pfvi_roll_back(r, st, N, t0);
    st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_KICK, .t0 = t0};
    return 0;
}

// The particle at the start q moved by the step's increments of x and v.
static inline void take_increments(struct reb_particle* p, const struct reb_particle* q,
        struct reb_vec3d dx, struct reb_vec3d dv){
    p->x = q->x + dx.x; p->y = q->y + dx.y; p->z = q->z + dx.z;
    p->vx = q->vx + dv.x; p->vy = q->vy + dv.y; p->vz = q->vz + dv.z;
}

static enum pfvi_trial two_point_advance(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h){
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const p0 = st->start;
    struct pfvi_end_state* const e = st->end;
    const int literal = (st->options.fitting == PFVI_FITTING_PHASE_LITERAL);
    // Unfitted, every centre is the origin at rest and u = 0: the step is
    // velocity Verlet, x += h (v + k a0) and v += k (a0 + a1) with k = h/2,
    // with the carried low-order parts; what follows with zero centres and
    // omega (the same numbers, spared the products with zeros).
    const int verlet = (st->options.fitting == PFVI_FITTING_NONE);

    // Kick with the residual force, then rotate with the harmonic flow about
    // the centre c(t) = c0 + (t - t0) vc (pfvi_centre.c), in d = q - c and
    // w = v - vc. With cos u > 0 (always at the default u_max) the whole step
    // is an increment of x and v, added with compensated summation;
    // "phase-literal" and cos u < 0 use plain products and drop the carried
    // low-order parts.
    for (size_t i=0; verlet && i<N; i++){
        const struct reb_particle* const q = &p0[i];
        const double* const a = e[i].a;
        const double k = st->fit[i].half_kick, h_drift = st->fit[i].h_sinc_u;
        const struct pfvi_compensation* const comp = &st->compensation[i];
        const double kick[3] = {k*a[0], k*a[1], k*a[2]};
        st->dx[i] = (struct reb_vec3d){h_drift*(q->vx + kick[0]) + comp->x[0],
            h_drift*(q->vy + kick[1]) + comp->x[1], h_drift*(q->vz + kick[2]) + comp->x[2]};
        st->dv[i] = (struct reb_vec3d){kick[0] + comp->v[0], kick[1] + comp->v[1], kick[2] + comp->v[2]};
        take_increments(&ps[i], q, st->dx[i], st->dv[i]);
    }
    for (size_t i=0; !verlet && i<N; i++){
        const struct reb_particle* const q = &p0[i];
        const double* const a = e[i].a;
        const struct pfvi_two_point_fit* const f = &st->fit[i];
        const struct pfvi_compensation* const comp = &st->compensation[i];
        const struct pfvi_centre* const c = &st->centre[i];
        const double d[3] = {q->x - c->x[0], q->y - c->x[1], q->z - c->x[2]};
        const double w2 = f->omega*f->omega;
        const double kick_x = f->half_kick*((a[0] - c->acc[0]) + w2*d[0]);
        const double kick_y = f->half_kick*((a[1] - c->acc[1]) + w2*d[1]);
        const double kick_z = f->half_kick*((a[2] - c->acc[2]) + w2*d[2]);
        // The centre's own motion over the step less what the rotation of
        // w = v - vc moves: (h - h sinc u) vc + h^2 ac/2.
        const double drift = h - f->h_sinc_u;
        const double shift[3] = {drift*c->v[0] + 0.5*h*h*c->acc[0], drift*c->v[1] + 0.5*h*h*c->acc[1],
            drift*c->v[2] + 0.5*h*h*c->acc[2]};
        const double k = f->keep, rc = f->cos_u_m_keep;
        if (!literal && k == 1.){
            const double vx = q->vx + kick_x, vy = q->vy + kick_y, vz = q->vz + kick_z;
            st->dx[i] = (struct reb_vec3d){
                ((rc*d[0] + f->h_sinc_u*vx) + shift[0]) + comp->x[0],
                ((rc*d[1] + f->h_sinc_u*vy) + shift[1]) + comp->x[1],
                ((rc*d[2] + f->h_sinc_u*vz) + shift[2]) + comp->x[2]};
            st->dv[i] = (struct reb_vec3d){
                (kick_x + (rc*(vx - c->v[0]) - f->omega_sin_u*d[0]) + h*c->acc[0]) + comp->v[0],
                (kick_y + (rc*(vy - c->v[1]) - f->omega_sin_u*d[1]) + h*c->acc[1]) + comp->v[1],
                (kick_z + (rc*(vz - c->v[2]) - f->omega_sin_u*d[2]) + h*c->acc[2]) + comp->v[2]};
            take_increments(&ps[i], q, st->dx[i], st->dv[i]);
        }else{
            const double g = literal ? f->gamma : 1.;
            const double wx = (q->vx - c->v[0])/g + kick_x, wy = (q->vy - c->v[1])/g + kick_y,
                wz = (q->vz - c->v[2])/g + kick_z;
            ps[i].x = (c->x[0] + pfvi_centre_shift(c, h, 0)) + (k*d[0] + (rc*d[0] + f->h_sinc_u*wx));
            ps[i].y = (c->x[1] + pfvi_centre_shift(c, h, 1)) + (k*d[1] + (rc*d[1] + f->h_sinc_u*wy));
            ps[i].z = (c->x[2] + pfvi_centre_shift(c, h, 2)) + (k*d[2] + (rc*d[2] + f->h_sinc_u*wz));
            ps[i].vx = pfvi_centre_velocity(c, h, 0) + (k*wx + (rc*wx - f->omega_sin_u*d[0]));
            ps[i].vy = pfvi_centre_velocity(c, h, 1) + (k*wy + (rc*wy - f->omega_sin_u*d[1]));
            ps[i].vz = pfvi_centre_velocity(c, h, 2) + (k*wz + (rc*wz - f->omega_sin_u*d[2]));
        }
    }
    const int compensated = !literal;
    // The variational particles: the tangent of the same kick and rotation
    // (their real particle's fit, about a centre frozen over the step: d =
    // delta q, w = delta v), placed at the end for the same force evaluation.
    for (size_t v=0; v<st->var_N; v++){
        const struct pfvi_two_point_fit* const f = &st->fit[st->var_real[v]];
        const struct reb_particle* const q = &st->var_start[v];
        const double* const a = st->var_end[v].a;
        const double w2 = f->omega*f->omega;
        const double g = literal ? f->gamma : 1.;
        const double d[3] = {q->x, q->y, q->z};
        const double w[3] = {q->vx/g + f->half_kick*(a[0] + w2*d[0]), q->vy/g + f->half_kick*(a[1] + w2*d[1]),
            q->vz/g + f->half_kick*(a[2] + w2*d[2])};
        const double k = f->keep, rc = f->cos_u_m_keep;
        struct reb_particle* const p = &r->particles_var[v];
        p->x = k*d[0] + (rc*d[0] + f->h_sinc_u*w[0]);
        p->y = k*d[1] + (rc*d[1] + f->h_sinc_u*w[1]);
        p->z = k*d[2] + (rc*d[2] + f->h_sinc_u*w[2]);
        st->var_dv[v] = (struct reb_vec3d){k*w[0] + (rc*w[0] - f->omega_sin_u*d[0]),
            k*w[1] + (rc*w[1] - f->omega_sin_u*d[1]), k*w[2] + (rc*w[2] - f->omega_sin_u*d[2])};
    }

    r->t = t0 + h;
    if (!pfvi_update_acceleration(r, st, N, t0)){
        return PFVI_TRIAL_ERROR;
    }
    // Final kick; implicit only if the force depends on velocities.
    if (r->force_is_velocity_dependent){
        for (size_t i=0; i<N; i++){
            st->v_rotated[i] = (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
        }
        if (!final_kick_velocity_dependent(r, st, N, t0, h)){
            return PFVI_TRIAL_ERROR;
        }
    }
    for (size_t i=0; verlet && i<N; i++){
        const double k = st->fit[i].half_kick;
        st->dv[i].x += k*ps[i].ax; st->dv[i].y += k*ps[i].ay; st->dv[i].z += k*ps[i].az;
        ps[i].vx = p0[i].vx + st->dv[i].x;
        ps[i].vy = p0[i].vy + st->dv[i].y;
        ps[i].vz = p0[i].vz + st->dv[i].z;
    }
    for (size_t i=0; !verlet && i<N; i++){
        const struct pfvi_two_point_fit* const f = &st->fit[i];
        const double w2 = f->omega*f->omega;
        double d[3];
        end_offset(st, &ps[i], i, h, d);
        const struct pfvi_centre* const c = &st->centre[i];
        const double kick_x = f->half_kick*((ps[i].ax - c->acc[0]) + w2*d[0]);
        const double kick_y = f->half_kick*((ps[i].ay - c->acc[1]) + w2*d[1]);
        const double kick_z = f->half_kick*((ps[i].az - c->acc[2]) + w2*d[2]);
        if (compensated && f->keep == 1.){
            st->dv[i].x += kick_x; st->dv[i].y += kick_y; st->dv[i].z += kick_z;
            ps[i].vx = p0[i].vx + st->dv[i].x;
            ps[i].vy = p0[i].vy + st->dv[i].y;
            ps[i].vz = p0[i].vz + st->dv[i].z;
        }else{
            const struct reb_vec3d vr = r->force_is_velocity_dependent ? st->v_rotated[i]
                : (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
            const double g = literal ? f->gamma : 1.;
            const double vc[3] = {pfvi_centre_velocity(c, h, 0), pfvi_centre_velocity(c, h, 1),
                pfvi_centre_velocity(c, h, 2)};
            ps[i].vx = vc[0] + g*((vr.x - vc[0]) + kick_x);
            ps[i].vy = vc[1] + g*((vr.y - vc[1]) + kick_y);
            ps[i].vz = vc[2] + g*((vr.z - vc[2]) + kick_z);
        }
    }
    // The variational particles' final kick, with their forces at the end.
    for (size_t v=0; v<st->var_N; v++){
        const struct pfvi_two_point_fit* const f = &st->fit[st->var_real[v]];
        struct reb_particle* const p = &r->particles_var[v];
        const double w2 = f->omega*f->omega;
        const double g = literal ? f->gamma : 1.;
        const double x1[3] = {p->x, p->y, p->z}, a1[3] = {p->ax, p->ay, p->az};
        p->vx = g*(st->var_dv[v].x + f->half_kick*(a1[0] + w2*x1[0]));
        p->vy = g*(st->var_dv[v].y + f->half_kick*(a1[1] + w2*x1[1]));
        p->vz = g*(st->var_dv[v].z + f->half_kick*(a1[2] + w2*x1[2]));
    }
    if (r->calculate_megno && st->var_N){
        // ln|delta| of REBOUND's MEGNO set (the first N variational particles)
        // at the two nodes, the trapezoidal rule between (docs/megno.md).
        const size_t n_megno = (r->N < st->var_N) ? r->N : st->var_N;
        double start = 0., end = 0.;
        for (size_t v=0; v<n_megno; v++){
            const struct reb_particle* const p0 = &st->var_start[v];
            const struct reb_particle* const p1 = &r->particles_var[v];
            start += (p0->x*p0->x + p0->y*p0->y + p0->z*p0->z) + (p0->vx*p0->vx + p0->vy*p0->vy + p0->vz*p0->vz);
            end += (p1->x*p1->x + p1->y*p1->y + p1->z*p1->z) + (p1->vx*p1->vx + p1->vy*p1->vy + p1->vz*p1->vz);
        }
        const double L0 = 0.5*log(start), L1 = 0.5*log(end);
        const double t_rel = t0 - r->megno_initial_t;
        st->trial.megno_dY = megno_increment(t_rel, h, L0, L1, 0.5*h*(L0 + L1));
        st->trial.megno_Y_integral = 0.5*h*(megno_Y(r->megno_Ys, t_rel) + megno_Y(r->megno_Ys + st->trial.megno_dY, t_rel + h));
    }
    st->trial.rounds = 1;
    return PFVI_TRIAL_OK;
}

// Half the trace of the step's map of (d, w) for a 1-D particle pulled
// towards its centre at frequency W: kick with (omega^2 - W^2) d, rotate,
// kick again gives cos u - (W^2/omega^2 - 1) sin u tan u/2, u = omega h,
// written so that omega = 0 (Verlet) needs no division.
static double two_point_half_trace(const struct pfvi_state* st, size_t i, double h, double W2){
    (void)h;   // (the fit already holds u = omega h)
    const struct pfvi_two_point_fit* const f = &st->fit[i];
    const double cos_u = f->keep + f->cos_u_m_keep;
    // sin u tan u = omega sin u * (h sinc u)/cos u; (W h sinc u)^2/cos u.
    return cos_u + 0.5*(f->omega_sin_u*f->h_sinc_u - W2*f->h_sinc_u*f->h_sinc_u)/cos_u;
}

// The step is taken: keep what the sums of x and v lost.
static void two_point_commit(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h){
    (void)h;
    const struct reb_particle* const ps = r->particles;
    const struct reb_particle* const p0 = st->start;
    const int compensated = (st->options.fitting != PFVI_FITTING_PHASE_LITERAL);
    for (size_t i=0; i<N; i++){
        struct pfvi_compensation* const comp = &st->compensation[i];
        if (compensated && st->fit[i].keep == 1.){
            comp->x[0] = st->dx[i].x - (ps[i].x - p0[i].x);
            comp->x[1] = st->dx[i].y - (ps[i].y - p0[i].y);
            comp->x[2] = st->dx[i].z - (ps[i].z - p0[i].z);
            comp->v[0] = st->dv[i].x - (ps[i].vx - p0[i].vx);
            comp->v[1] = st->dv[i].y - (ps[i].vy - p0[i].vy);
            comp->v[2] = st->dv[i].z - (ps[i].vz - p0[i].vz);
        }else{
            *comp = (struct pfvi_compensation){{0., 0., 0.}, {0., 0., 0.}};
        }
    }
    st->predictor_stages = 0;
}

// The start acceleration (the last step's end one) and the end one.
static void two_point_stage_accelerations(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
        double (*a)[3]){
    const struct reb_particle* const p = &r->particles[i];
    for (int c=0; c<3; c++){
        a[0][c] = st->end[i].a[c];
    }
    a[1][0] = p->ax; a[1][1] = p->ay; a[1][2] = p->az;
}

static void two_point_stage_positions(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
        double (*x)[3]){
    const struct reb_particle* const p0 = &st->start[i];
    const struct reb_particle* const p = &r->particles[i];
    x[0][0] = p0->x; x[0][1] = p0->y; x[0][2] = p0->z;
    x[1][0] = p->x; x[1][1] = p->y; x[1][2] = p->z;
}

const struct pfvi_scheme pfvi_two_point_scheme = {
    .prepare = two_point_prepare,
    .fit = two_point_fit,
    .copy_fit = two_point_copy_fit,
    .fitted_omega = two_point_fitted_omega,
    .advance = two_point_advance,
    .commit = two_point_commit,
    .stage_accelerations = two_point_stage_accelerations,
    .stage_positions = two_point_stage_positions,
    .half_trace = two_point_half_trace,
};

/**
 * pfvi_two_point.c: the two-point scheme (stages = 2; K&V section 3), an
 * explicit step with the closed form of pfvi_fitting.c: kick with the
 * residual force a + omega^2 q, rotate with the harmonic flow at omega, kick
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

// Implicit final kick for velocity-dependent forces: v = vr + k (a(q, v) + omega^2 q),
// by fixed-point iteration under the common stopping rule.
static int final_kick_velocity_dependent(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    struct reb_particle* const ps = r->particles;
    const struct pfvi_two_point_fit* const fit = st->fit;
    double previous = INFINITY;
    for (int iteration=0; iteration<PFVI_ITERATION_MAX; iteration++){
        double change = 0., scale = 0.;
        for (size_t i=0; i<N; i++){
            const double w2 = fit[i].omega*fit[i].omega;
            const double k = fit[i].half_kick;
            const double vx = st->v_rotated[i].x + k*(ps[i].ax + w2*ps[i].x);
            const double vy = st->v_rotated[i].y + k*(ps[i].ay + w2*ps[i].y);
            const double vz = st->v_rotated[i].z + k*(ps[i].az + w2*ps[i].z);
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

static enum pfvi_trial two_point_advance(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h){
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const p0 = st->start;
    struct pfvi_end_state* const e = st->end;
    const int literal = (st->options.fitting == PFVI_FITTING_PHASE_LITERAL);

    // Kick with the residual force, then rotate with the harmonic flow. With
    // cos u > 0 (always at the default u_max) the whole step is an increment
    // of x and v, added with compensated summation; "phase-literal" and
    // cos u < 0 use plain products and drop the carried low-order parts.
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const q = &p0[i];
        const double* const a = e[i].a;
        const struct pfvi_two_point_fit* const f = &st->fit[i];
        const struct pfvi_compensation* const comp = &st->compensation[i];
        const double w2 = f->omega*f->omega;
        const double kick_x = f->half_kick*(a[0] + w2*q->x);
        const double kick_y = f->half_kick*(a[1] + w2*q->y);
        const double kick_z = f->half_kick*(a[2] + w2*q->z);
        const double k = f->keep, rc = f->cos_u_m_keep;
        if (!literal && k == 1.){
            const double vx = q->vx + kick_x, vy = q->vy + kick_y, vz = q->vz + kick_z;
            st->dx[i] = (struct reb_vec3d){
                (rc*q->x + f->h_sinc_u*vx) + comp->x[0],
                (rc*q->y + f->h_sinc_u*vy) + comp->x[1],
                (rc*q->z + f->h_sinc_u*vz) + comp->x[2]};
            st->dv[i] = (struct reb_vec3d){
                kick_x + (rc*vx - f->omega_sin_u*q->x) + comp->v[0],
                kick_y + (rc*vy - f->omega_sin_u*q->y) + comp->v[1],
                kick_z + (rc*vz - f->omega_sin_u*q->z) + comp->v[2]};
            ps[i].x = q->x + st->dx[i].x;
            ps[i].y = q->y + st->dx[i].y;
            ps[i].z = q->z + st->dx[i].z;
            ps[i].vx = q->vx + st->dv[i].x;
            ps[i].vy = q->vy + st->dv[i].y;
            ps[i].vz = q->vz + st->dv[i].z;
        }else{
            const double g = literal ? f->gamma : 1.;
            const double vx = q->vx/g + kick_x, vy = q->vy/g + kick_y, vz = q->vz/g + kick_z;
            ps[i].x = k*q->x + (rc*q->x + f->h_sinc_u*vx);
            ps[i].y = k*q->y + (rc*q->y + f->h_sinc_u*vy);
            ps[i].z = k*q->z + (rc*q->z + f->h_sinc_u*vz);
            ps[i].vx = k*vx + (rc*vx - f->omega_sin_u*q->x);
            ps[i].vy = k*vy + (rc*vy - f->omega_sin_u*q->y);
            ps[i].vz = k*vz + (rc*vz - f->omega_sin_u*q->z);
        }
    }
    const int compensated = !literal;

    r->t = t0 + h;
    if (!pfvi_update_acceleration(r, st, N, t0)){
        return PFVI_TRIAL_ERROR;
    }
    // Final kick; implicit only if the force depends on velocities.
    if (r->force_is_velocity_dependent){
        for (size_t i=0; i<N; i++){
            st->v_rotated[i] = (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
        }
        if (!final_kick_velocity_dependent(r, st, N, t0)){
            return PFVI_TRIAL_ERROR;
        }
    }
    for (size_t i=0; i<N; i++){
        const struct pfvi_two_point_fit* const f = &st->fit[i];
        const double w2 = f->omega*f->omega;
        const double kick_x = f->half_kick*(ps[i].ax + w2*ps[i].x);
        const double kick_y = f->half_kick*(ps[i].ay + w2*ps[i].y);
        const double kick_z = f->half_kick*(ps[i].az + w2*ps[i].z);
        if (compensated && f->keep == 1.){
            st->dv[i].x += kick_x; st->dv[i].y += kick_y; st->dv[i].z += kick_z;
            ps[i].vx = p0[i].vx + st->dv[i].x;
            ps[i].vy = p0[i].vy + st->dv[i].y;
            ps[i].vz = p0[i].vz + st->dv[i].z;
        }else{
            const struct reb_vec3d vr = r->force_is_velocity_dependent ? st->v_rotated[i]
                : (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
            const double g = literal ? f->gamma : 1.;
            ps[i].vx = g*(vr.x + kick_x);
            ps[i].vy = g*(vr.y + kick_y);
            ps[i].vz = g*(vr.z + kick_z);
        }
    }
    st->trial.rounds = 1;
    return PFVI_TRIAL_OK;
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

const struct pfvi_scheme pfvi_two_point_scheme = {
    .prepare = two_point_prepare,
    .fit = two_point_fit,
    .copy_fit = two_point_copy_fit,
    .fitted_omega = two_point_fitted_omega,
    .advance = two_point_advance,
    .commit = two_point_commit,
};

/**
 * pfvi_stages.c: the s-point scheme (stages = 3 .. 8): the discrete Lagrangian
 * with interior corrections of K&V, "Increasing the algebraic order".
 *
 * Per particle and per Cartesian component (units of unit mass), the step
 * solves, for the unknowns Delta = q_k+1 - q_k and delta q^j (interior j),
 *     sum_k w_k [B^k qd^k + h^2 b^k a^k]     = -G h v_k         (p_k = -D1 Ld)
 *     sum_k w_k a^k_j qd^k + h^2 w_j a^j     = 0                (dLd/d delta q^j = 0)
 * with qd^k = h qdot^k = beta_d^k q_k + Bbar^k Delta + sum_l a^k_l delta q^l and
 * a^k the acceleration at the stage point q^k = (1 + beta_m^k) q_k + bbar^k Delta
 * + delta q^k at t_k + c^k h, and then takes
 *     G h (v_k+1 - v_k) = sum_k w_k [beta_d^k qd^k + h^2 (b^k + bbar^k) a^k]
 * (p_k+1 = D2 Ld minus p_k = -D1 Ld). For given a^k the equations are linear
 * with a matrix L that depends only on u (factorised in pfvi_fitting.c): a
 * round solves the linear system for the forces F at the stage points (y =
 * L^-1 g - (L^-1 P) F, P their weights), the forces come through REBOUND,
 * and the solve layer (pfvi_solve.c) corrects the rounds by Newton's method
 * and stops them; a solve that does not converge is retried shorter or
 * refused.
 *
 * The first iterate: a retried step's converged stages, or else (classical
 * form) the two-body predictor of pfvi_solve.c; the fitted form's from the
 * previous step's stage accelerations, extrapolated by their polynomial.
 */
#include <float.h>
#include <math.h>
#include <string.h>
#include "pfvi.h"

// A variational particle's tangent step is its real particle's step with the
// centre and omega frozen (pfvi.h, var_N): the same fit, about a centre
// whose tangent is zero, and no carried low-order parts (a tangent vector's
// round-off relative to itself stays at the doubles' level; it is never
// added to a much larger coordinate).
static const struct pfvi_centre var_centre = {{0., 0., 0.}, {0., 0., 0.}, {0., 0., 0.}, {0., 0., 0.}, 0., SIZE_MAX};
static const struct pfvi_compensation var_compensation = {{0., 0., 0.}, {0., 0., 0.}};

// The part of the stage equations a step's rounds share (per particle): the
// unknowns for zero force, L^-1 g with g the start momentum and position
// terms, and the stage points' parts that do not depend on the unknowns.
static void stage_start_of(const struct pfvi_lobatto* rule, const struct pfvi_stage_fit* f,
        const struct reb_particle* p0, const struct pfvi_centre* centre, double h, struct pfvi_stage_start* ss){
    const int s = rule->s, m = s - 1;
    const double q0[3] = {p0->x, p0->y, p0->z};
    ss->v0[0] = p0->vx; ss->v0[1] = p0->vy; ss->v0[2] = p0->vz;
    if (f->classical){
        // The classical form needs the start only (it knows no centre).
        ss->q0[0] = q0[0]; ss->q0[1] = q0[1]; ss->q0[2] = q0[2];
        return;
    }
    const double v0[3] = {p0->vx - centre->v[0], p0->vy - centre->v[1], p0->vz - centre->v[2]};
    for (int c=0; c<3; c++){
        ss->q0[c] = q0[c];
        ss->d0[c] = q0[c] - centre->x[c];
        const double momentum = f->G*h*v0[c];
        for (int l=0; l<PFVI_STAGES_MAX-1; l++){
            ss->yc[l][c] = (l < m) ? -(momentum*f->start_momentum[l] + ss->d0[c]*f->start_offset[l]) : 0.;
        }
        for (int k=0; k<PFVI_STAGES_MAX; k++){
            ss->base[k][c] = (k < s) ? f->beta_m[k]*ss->d0[c] : 0.;
            ss->shift[k][c] = (k < s) ? pfvi_centre_shift(centre, rule->c[k]*h, c) : 0.;
        }
    }
}

// h^2 times the force the iteration carries at stage k, component c: the
// acceleration relative to the centre's, and for "exact" (u2 > 0) plus
// u^2 d^k at the point sx where it was evaluated (the residual of the
// harmonic part the matrix holds).
static inline double stage_force_h2(const struct pfvi_stage_fit* f, const struct pfvi_stage_start* ss,
        const struct pfvi_centre* centre, double h, const double (*sa)[3], const double (*sx)[3], int k, int c){
    const double h2a = h*h*(sa[k][c] - centre->acc[c]);
    if (f->u2 == 0.){
        return h2a;
    }
    return h2a + f->u2*((sx[k][c] - centre->x[c]) - ss->shift[k][c]);
}

// One round for one particle: the unknowns y for the forces F the iteration
// carries (stage_force_h2, at the stage accelerations sa evaluated at the
// points sx): y = yc - solve F. Written
// for a constant s, so that each s gets its own fully unrolled loops.
static inline __attribute__((always_inline)) void stage_round_n(const struct pfvi_stage_fit* f,
        const struct pfvi_stage_start* ss, const struct pfvi_centre* centre, double h, const double (*sa)[3],
        const double (*sx)[3], double (*y)[3], const int s){
    double F[PFVI_STAGES_MAX][3];
    for (int k=0; k<s; k++){
        for (int c=0; c<3; c++){
            F[k][c] = stage_force_h2(f, ss, centre, h, sa, sx, k, c);
        }
    }
    for (int l=0; l<s-1; l++){
        double sum[3] = {0., 0., 0.};
        for (int k=0; k<s; k++){
            for (int c=0; c<3; c++){
                sum[c] += f->solve[l][k]*F[k][c];
            }
        }
        for (int c=0; c<3; c++){
            y[l][c] = ss->yc[l][c] - sum[c];
        }
    }
}

// One round of the classical form for one particle (the rule's Runge-Kutta-
// Nystrom form of Lobatto IIIA-IIIB, pfvi.h): with hb_j = h w_j and the
// stage accelerations A^j the iteration carries, the unknowns
//     y[i-1] = Q^i - q_k = c_nu[i] h v_k + h sum_j nu[i][j] hb_j A^j
// (i = 1 .. s-1; y[s-2] = q_k+1 - q_k). The last column of nu is zero: the
// end force A^s does not act within the step it ends.
typedef char two_lanes_cover_the_stages[(PFVI_STAGES_MAX == 8) ? 1 : -1];

static inline __attribute__((always_inline)) void classical_round_n(const struct pfvi_lobatto* rule,
        const struct pfvi_stage_start* ss, double h, const double* hb, const double (*sa)[3], double (*y)[3],
        const int s){
    // Each row i's sum over j in ascending order, as a scalar loop adds it,
    // with the rows as vector lanes (nu_t: a column of nu contiguous): each
    // lane rounds as the scalar sum would, so every vector width gives the
    // same bits. Lanes 0 .. 3 and 4 .. 7, for the three components.
    pfvi_lanes lo[3] = {{0.}}, hi[3] = {{0.}};
    for (int j=0; j<s-1; j++){
        pfvi_lanes nl, nh;
        memcpy(&nl, &rule->nu_t[j][0], sizeof(nl));
        memcpy(&nh, &rule->nu_t[j][4], sizeof(nh));
        for (int c=0; c<3; c++){
            const double hbA = hb[j]*sa[j][c];
            const pfvi_lanes b = {hbA, hbA, hbA, hbA};
            lo[c] += nl*b;
            hi[c] += nh*b;
        }
    }
    for (int c=0; c<3; c++){
        double sum[PFVI_STAGES_MAX];
        memcpy(sum, &lo[c], sizeof(lo[c]));
        memcpy(sum + 4, &hi[c], sizeof(hi[c]));
        const double hv = h*ss->v0[c];
        for (int i=1; i<s; i++){
            y[i-1][c] = rule->c_nu[i]*hv + h*sum[i];
        }
    }
}

PFVI_VECTOR_CLONES
static void classical_round(const struct pfvi_lobatto* rule, const struct pfvi_stage_start* ss, double h,
        const double* hb, const double (*sa)[3], double (*y)[3]){
    switch (rule->s){
        case 3: classical_round_n(rule, ss, h, hb, sa, y, 3); break;
        case 4: classical_round_n(rule, ss, h, hb, sa, y, 4); break;
        case 5: classical_round_n(rule, ss, h, hb, sa, y, 5); break;
        case 6: classical_round_n(rule, ss, h, hb, sa, y, 6); break;
        case 7: classical_round_n(rule, ss, h, hb, sa, y, 7); break;
        default: classical_round_n(rule, ss, h, hb, sa, y, PFVI_STAGES_MAX); break;
    }
}

// The classical form's stage velocities (IIIB) for the accelerations sa.
static void classical_velocities(const struct pfvi_lobatto* rule, const struct pfvi_stage_start* ss,
        const double* hb, const double (*sa)[3], double (*V)[3]){
    const int s = rule->s;
    for (int k=0; k<s; k++){
        for (int c=0; c<3; c++){
            double sum = 0.;
            for (int j=0; j<s-1; j++){
                sum += rule->mu_hat[k][j]*(hb[j]*sa[j][c]);
            }
            V[k][c] = ss->v0[c] + sum;
        }
    }
}

// One case per s from 3 to PFVI_STAGES_MAX.
typedef char pfvi_stage_round_has_a_case_per_s[(PFVI_STAGES_MAX == 8) ? 1 : -1];

static void stage_round(const struct pfvi_stage_fit* f, const struct pfvi_stage_start* ss,
        const struct pfvi_centre* centre, int s, double h, const double (*sa)[3], const double (*sx)[3],
        double (*y)[3]){
    switch (s){
        case 3: stage_round_n(f, ss, centre, h, sa, sx, y, 3); break;
        case 4: stage_round_n(f, ss, centre, h, sa, sx, y, 4); break;
        case 5: stage_round_n(f, ss, centre, h, sa, sx, y, 5); break;
        case 6: stage_round_n(f, ss, centre, h, sa, sx, y, 6); break;
        case 7: stage_round_n(f, ss, centre, h, sa, sx, y, 7); break;
        default: stage_round_n(f, ss, centre, h, sa, sx, y, PFVI_STAGES_MAX); break;
    }
}

// The step's position increment q_k+1 - q_k of one component: the change
// of d = q - c and the centre's drift.
static inline double stage_increment(const struct pfvi_stage_fit* f, const struct pfvi_stage_start* ss,
        const double (*y)[3], int s, int c){
    return f->classical ? y[s-2][c] : y[0][c] + ss->shift[s-1][c];
}

// Stage point k of one particle: q_k + (beta_m d_k + bbar (d_k+1 - d_k)
// + delta q^k + the centre's drift). The last stage is q_k + (increment +
// carried low-order part, with the increment's own low part: low, or NULL),
// exactly the position the step will end on.
static inline void stage_position(const struct pfvi_stage_fit* f, const struct pfvi_stage_start* ss,
        const struct pfvi_compensation* comp, const double* low, const double (*y)[3], int s, int k, double x[3]){
    for (int c=0; c<3; c++){
        if (k == 0){
            x[c] = ss->q0[c];
        }else if (k == s - 1){
            x[c] = ss->q0[c] + (stage_increment(f, ss, y, s, c) + (comp->x[c] + (low ? low[c] : 0.)));
        }else if (f->classical){
            x[c] = ss->q0[c] + y[k-1][c];
        }else{
            x[c] = ss->q0[c] + ((ss->base[k][c] + f->bbar[k]*y[0][c] + y[k][c]) + ss->shift[k][c]);
        }
    }
}

// h ddot^k of one particle (its velocity relative to its centre, times h).
static void stage_velocity_times_h(const struct pfvi_stage_fit* f, const struct pfvi_stage_start* ss,
        const double (*y)[3], int s, int k, double qd[3]){
    for (int c=0; c<3; c++){
        double sum = f->beta_d[k]*ss->d0[c] + f->Bbar[k]*y[0][c];
        for (int l=1; l<s-1; l++){
            sum += f->a[k][l]*y[l][c];
        }
        qd[c] = sum;
    }
}

// stage_forces where REBOUND would compute only its basic gravity: every
// stage point of the iterate into stage_x, their forces in one pass
// (pfvi_gravity.c) into stage_a, and the particles and t left as REBOUND's
// trips leave them (at stage k_last). 0 where a force is not finite: the
// caller then takes REBOUND's path, which names the cause and rolls back.
// Every real particle's stage points k_first .. k_last of the iterate into stage_x.
static void stage_points(struct pfvi_state* st, size_t N, int k_first, int k_last){
    const int s = st->rule.s;
    for (size_t i=0; i<N; i++){
        const double (*y)[3] = (const double (*)[3])st->unknowns[i];
        if (st->stage_fit[i].classical && k_first >= 1){
            // stage_position of the classical form, its branches taken once:
            // the stages inside the step, then the end's if asked for.
            const double* const q0 = st->stage_start[i].q0;
            const double* const comp = st->compensation[i].x;
            const int k_inside = (k_last < s - 1) ? k_last : s - 2;
            for (int k=k_first; k<=k_inside; k++){
                st->stage_x[i][k][0] = q0[0] + y[k-1][0];
                st->stage_x[i][k][1] = q0[1] + y[k-1][1];
                st->stage_x[i][k][2] = q0[2] + y[k-1][2];
            }
            if (k_last == s - 1){
                const double* const low = st->end_low[i];
                for (int c=0; c<3; c++){
                    st->stage_x[i][s-1][c] = q0[c] + (y[s-2][c] + (comp[c] + low[c]));
                }
            }
            continue;
        }
        for (int k=k_first; k<=k_last; k++){
            stage_position(&st->stage_fit[i], &st->stage_start[i], &st->compensation[i], st->end_low[i], y, s, k,
                    st->stage_x[i][k]);
        }
    }
}

// n particles at their stage k's positions x and forces a.
static void particles_at(struct reb_particle* p, size_t n, const double (*x)[PFVI_STAGES_MAX][3],
        const double (*a)[PFVI_STAGES_MAX][3], int k){
    for (size_t i=0; i<n; i++){
        p[i].x = x[i][k][0]; p[i].y = x[i][k][1]; p[i].z = x[i][k][2];
        p[i].ax = a[i][k][0]; p[i].ay = a[i][k][1]; p[i].az = a[i][k][2];
    }
}

// The particles (the variational ones with nv > 0) and t as REBOUND's trip
// to stage k_last leaves them: its positions and forces.
static void particles_at_stage(struct reb_simulation* r, const struct pfvi_state* st, size_t N, size_t nv,
        double t0, double h, int k_last){
    particles_at(r->particles, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x,
            (const double (*)[PFVI_STAGES_MAX][3])st->stage_a, k_last);
    particles_at(r->particles_var, nv, (const double (*)[PFVI_STAGES_MAX][3])st->var_stage_x,
            (const double (*)[PFVI_STAGES_MAX][3])st->var_stage_a, k_last);
    r->t = t0 + st->rule.c[k_last]*h;
}

// The variational particles' tangent stage points k_first .. k_last into
// var_stage_x, and REBOUND's variational gravity there, at the real stage
// points of stage_x, into var_stage_a (pfvi_gravity.c).
static void variational_stage_forces(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        int k_first, int k_last){
    const int s = st->rule.s;
    for (size_t v=0; v<st->var_N; v++){
        for (int k=k_first; k<=k_last; k++){
            stage_position(&st->stage_fit[st->var_real[v]], &st->var_stage_start[v], &var_compensation, NULL,
                    (const double (*)[3])st->var_unknowns[v], s, k, st->var_stage_x[v][k]);
        }
    }
    pfvi_gravity_variational_stages(r, st, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x,
            (const double (*)[PFVI_STAGES_MAX][3])st->var_stage_x, st->var_stage_a, k_first, k_last);
}

static int stage_forces_own(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        int k_first, int k_last){
    stage_points(st, N, k_first, k_last);
    // (finite: pfvi_update_acceleration's check, made in the gravity's lanes)
    if (!pfvi_gravity_stages(r, st, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x, st->stage_a,
            k_first, k_last)){
        return 0;
    }
    st->statistics.n_force_evaluations += (uint64_t)(k_last - k_first + 1);
    particles_at_stage(r, st, N, 0, t0, h, k_last);
    return 1;
}

// stage_forces where REBOUND would compute its basic gravity and its basic
// variational gravity alone (MEGNO's variations, add_variation()'s): the
// real forces as stage_forces_own's (with real = 0 the real particles'
// stage points are their converged ones, in stage_x: the variational
// particles' tangent solve goes on alone), then the variational particles'
// at their tangent stage points in one pass (pfvi_gravity.c), and the
// particles and t left as REBOUND's trips leave them. 0 where a real force
// is not finite (REBOUND's path then names it).
static int stage_forces_own_variational(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0,
        double h, int real, int k_first, int k_last){
    if (real){
        stage_points(st, N, k_first, k_last);
        if (!pfvi_gravity_stages(r, st, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x, st->stage_a,
                k_first, k_last)){
            return 0;
        }
    }
    variational_stage_forces(r, st, N, k_first, k_last);
    st->statistics.n_force_evaluations += (uint64_t)(k_last - k_first + 1);
    particles_at_stage(r, st, N, st->var_N, t0, h, k_last);
    return 1;
}

// Evaluates the forces at every stage point of the current iterate (and at
// the first node too when forces depend on velocities, since its velocity is
// the interpolant's, not v_k). Returns 0, rolled back, on a failure.
// The variational particles are placed at their tangent stage points for
// the same calls (REBOUND computes their forces beside the real ones); with
// real = 0 only theirs are kept (the real particles placed at the same
// stage points as before, their stage values left as they are).
static int stage_forces(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h, int real,
        int k_first, int k_last){
    const struct pfvi_lobatto* const rule = &st->rule;
    const int s = rule->s;
    const int vdep = r->force_is_velocity_dependent;
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const pv = r->particles_var;
    const size_t nv = st->var_N;
    if (real && !vdep && pfvi_gravity_own(r, st, N) && stage_forces_own(r, st, N, t0, h, k_first, k_last)){
        return 1;
    }
    if (nv > 0 && !vdep && pfvi_gravity_own_variational(r, st, N)
            && stage_forces_own_variational(r, st, N, t0, h, real, k_first, k_last)){
        return 1;
    }
    if (vdep){
        // The stage velocities of the current iterate, from the forces that
        // made it (stage_a, overwritten below).
        double hb[PFVI_STAGES_MAX];
        for (int j=0; j<s; j++){
            hb[j] = h*rule->w[j];
        }
        for (size_t i=0; i<N; i++){
            if (st->stage_fit[i].classical){
                classical_velocities(rule, &st->stage_start[i], hb, (const double (*)[3])st->stage_a[i],
                        st->velocities[i]);
            }
        }
    }
    const int k_start = (vdep && k_first <= 1) ? 0 : k_first;
    // Where REBOUND's routine would compute its basic gravity before the
    // additional forces (a callback, REBOUNDx's), that gravity at every
    // stage in one pass, and at each stage the particles placed there with
    // it in their accelerations, as the routine leaves them, and the
    // additional forces called: the same calls and sums as REBOUND's. (A
    // gravity not finite: REBOUND's routine, which names the cause. The
    // stage forces the velocities above came from are read by then.)
    // With variational particles (never velocity-dependent forces: refused)
    // their gravity too, REBOUND's variational gravity at their tangent
    // stage points; while the tangent solve goes on alone (real = 0) the real
    // gravity at the converged stage points (stage_x) is computed for the
    // callback to find, into scratch, as REBOUND's routine would recompute it.
    int given = 0;
    double (*real_a)[PFVI_STAGES_MAX][3] = st->stage_a;
    if (real && nv == 0 && pfvi_gravity_own_beside_forces(r, st, N)){
        stage_points(st, N, k_start, k_last);
        given = pfvi_gravity_stages(r, st, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x, st->stage_a,
            k_start, k_last);
    }else if (nv > 0 && !vdep && pfvi_gravity_own_variational_beside_forces(r, st, N)){
        if (real){
            stage_points(st, N, k_start, k_last);
        }else{
            real_a = st->beside_a;
        }
        given = pfvi_gravity_stages(r, st, N, (const double (*)[PFVI_STAGES_MAX][3])st->stage_x, real_a,
            k_start, k_last);
        if (given){
            variational_stage_forces(r, st, N, k_start, k_last);
        }
    }
    for (int k=k_start; k<=k_last; k++){
        for (size_t v=0; v<nv; v++){
            double x[3];
            stage_position(&st->stage_fit[st->var_real[v]], &st->var_stage_start[v], &var_compensation, NULL,
                    (const double (*)[3])st->var_unknowns[v], s, k, x);
            pv[v].x = x[0]; pv[v].y = x[1]; pv[v].z = x[2];
        }
        for (size_t i=0; i<N; i++){
            double x[3];
            const struct pfvi_centre* const centre = &st->centre[i];
            stage_position(&st->stage_fit[i], &st->stage_start[i], &st->compensation[i], st->end_low[i],
                    (const double (*)[3])st->unknowns[i], s, k, x);
            ps[i].x = x[0]; ps[i].y = x[1]; ps[i].z = x[2];
            if (vdep && st->stage_fit[i].classical){
                ps[i].vx = st->velocities[i][k][0];
                ps[i].vy = st->velocities[i][k][1];
                ps[i].vz = st->velocities[i][k][2];
            }else if (vdep){
                double qd[3];
                stage_velocity_times_h(&st->stage_fit[i], &st->stage_start[i], (const double (*)[3])st->unknowns[i],
                        s, k, qd);
                const double t = rule->c[k]*h;
                ps[i].vx = pfvi_centre_velocity(centre, t, 0) + qd[0]/h;
                ps[i].vy = pfvi_centre_velocity(centre, t, 1) + qd[1]/h;
                ps[i].vz = pfvi_centre_velocity(centre, t, 2) + qd[2]/h;
            }
        }
        // (A callback may have changed what REBOUND's routine computes, past
        // what the step's force model keeps: REBOUND's gravity_ignore_terms.
        // From then on, its routine, as before.)
        const int gravity_given = given && (nv ? pfvi_gravity_own_variational_beside_forces(r, st, N)
                : pfvi_gravity_own_beside_forces(r, st, N));
        for (size_t i=0; gravity_given && i<N; i++){
            ps[i].ax = real_a[i][k][0]; ps[i].ay = real_a[i][k][1]; ps[i].az = real_a[i][k][2];
        }
        for (size_t v=0; gravity_given && v<nv; v++){
            pv[v].ax = st->var_stage_a[v][k][0]; pv[v].ay = st->var_stage_a[v][k][1];
            pv[v].az = st->var_stage_a[v][k][2];
        }
        r->t = t0 + rule->c[k]*h;
        if (!(gravity_given ? pfvi_update_additional_forces(r, st, N, t0) : pfvi_update_acceleration(r, st, N, t0))){
            return 0;
        }
        for (size_t v=0; v<nv; v++){
            st->var_stage_x[v][k][0] = pv[v].x;
            st->var_stage_x[v][k][1] = pv[v].y;
            st->var_stage_x[v][k][2] = pv[v].z;
            st->var_stage_a[v][k][0] = pv[v].ax;
            st->var_stage_a[v][k][1] = pv[v].ay;
            st->var_stage_a[v][k][2] = pv[v].az;
        }
        for (size_t i=0; real && i<N; i++){
            st->stage_x[i][k][0] = ps[i].x;
            st->stage_x[i][k][1] = ps[i].y;
            st->stage_x[i][k][2] = ps[i].z;
            st->stage_a[i][k][0] = ps[i].ax;
            st->stage_a[i][k][1] = ps[i].ay;
            st->stage_a[i][k][2] = ps[i].az;
        }
    }
    return 1;
}

// First iterate of the stage accelerations, along an interpolating
// polynomial of converged ones: those of the last trial of this same step
// (a trial the step control rejected, or retries at another h), or else the
// last step's, extrapolated; without either, the start acceleration at every
// node. Returns which (the classical form starts from a retry's, otherwise
// from the two-body predictor of pfvi_solve.c, which extrapolates only the
// forces beyond each body's partner, from the last step's stages).
// With tangent_only (a classical step whose first iterate the two-body
// predictor draws) the real particles' stages beyond the start would be
// only placeholders, overwritten unread: stages 1 .. s-2 by the solve's
// first forces, the end by the converged step's (the classical round does
// not read it; a solve that fails leaves no retry): only the start is
// written, and their polynomial is not evaluated. The variational
// particles' stages are drawn either way.
static int stage_predict(struct pfvi_state* st, size_t N, double t0, double h, int tangent_only){
    const struct pfvi_lobatto* const rule = &st->rule;
    const int s = rule->s;
    // Extrapolated over more than a few of the source's lengths (a step
    // after a much shorter one) the polynomial leaves the plausible: the
    // Taylor path of the start state then.
    const double ratio_max = PFVI_PREDICTOR_RATIO_MAX;
    const int retry = st->retry_valid && st->retry_t0 == t0 && st->retry_stages == s && st->retry_h != 0.
        && fabs(h) <= ratio_max*fabs(st->retry_h);
    const int extrapolate = !retry && st->predictor_stages == s && st->predictor_N == N && st->predictor_t == t0
        && st->predictor_h != 0. && fabs(h) <= ratio_max*fabs(st->predictor_h);
    const int polynomial = retry || (extrapolate && !tangent_only);
    const int var_retry = retry && st->var_retry_valid;
    const int var_extrapolate = extrapolate && st->var_predictor_N == st->var_N;
    const int var_polynomial = var_retry || var_extrapolate;
    double x[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    if (polynomial || (st->var_N && var_polynomial)){
        // x[j][m] = l_m(tau_j): the Lagrange basis of the source's nodes at
        // this step's, in units of the source's step (which starts at t0 for
        // a retry, and ends there for the last step).
        const double rho = h/(retry ? st->retry_h : st->predictor_h);
        for (int j=0; j<s; j++){
            pfvi_lagrange_at(rule, (retry ? 0. : 1.) + rho*rule->c[j], x[j]);
        }
    }
    const struct reb_particle* const p0 = st->start;
    const int k_end = (tangent_only && !retry) ? 1 : s;   // stages written
    for (size_t i=0; i<N; i++){
        // A retry reads the values it overwrites: this particle's, copied first.
        double source[PFVI_STAGES_MAX][3], source_x[PFVI_STAGES_MAX][3];
        for (int m=0; polynomial && m<s; m++){
            for (int c=0; c<3; c++){
                source[m][c] = retry ? st->stage_a[i][m][c] : (extrapolate ? st->predictor_a[i][m][c] : 0.);
                source_x[m][c] = retry ? st->stage_x[i][m][c] : (extrapolate ? st->predictor_x[i][m][c] : 0.);
            }
        }
        const double q0[3] = {p0[i].x, p0[i].y, p0[i].z};
        const double v0[3] = {p0[i].vx, p0[i].vy, p0[i].vz};
        for (int k=0; k<k_end; k++){
            for (int c=0; c<3; c++){
                if (k == 0 || !polynomial){
                    // The start acceleration, at the start position moved along its tangent.
                    const double t = rule->c[k]*h;
                    st->stage_a[i][k][c] = st->end[i].a[c];
                    st->stage_x[i][k][c] = (k == 0) ? q0[c] : q0[c] + t*(v0[c] + 0.5*t*st->end[i].a[c]);
                }else{
                    double sum = 0., sum_x = 0.;
                    for (int m=0; m<s; m++){
                        sum += x[k][m]*source[m][c];
                        sum_x += x[k][m]*source_x[m][c];
                    }
                    st->stage_a[i][k][c] = sum;
                    // (positions from an archive written before they were saved are not numbers)
                    const double t = rule->c[k]*h;
                    st->stage_x[i][k][c] = isfinite(sum_x) ? sum_x : q0[c] + t*(v0[c] + 0.5*t*st->end[i].a[c]);
                }
            }
        }
    }
    // The variational particles' stages, from their own last trial or step
    // along the same polynomial, where they were taken with these particles.
    for (size_t v=0; v<st->var_N; v++){
        const int classical = st->stage_fit[st->var_real[v]].classical;
        double source[PFVI_STAGES_MAX][3], source_x[PFVI_STAGES_MAX][3];
        for (int m=0; m<s; m++){
            for (int c=0; c<3; c++){
                source[m][c] = var_retry ? st->var_stage_a[v][m][c] : (var_extrapolate ? st->var_predictor_a[v][m][c] : 0.);
                source_x[m][c] = var_retry ? st->var_stage_x[v][m][c] : (var_extrapolate ? st->var_predictor_x[v][m][c] : 0.);
            }
        }
        const struct reb_particle* const p = &st->var_start[v];
        const double q0[3] = {p->x, p->y, p->z};
        const double v0[3] = {p->vx, p->vy, p->vz};
        const double* const a0 = st->var_end[v].a;
        for (int k=0; k<s; k++){
            for (int c=0; c<3; c++){
                const double t = rule->c[k]*h;
                if (k == 0 || !var_polynomial){
                    st->var_stage_a[v][k][c] = a0[c];
                    st->var_stage_x[v][k][c] = (k == 0) ? q0[c] : q0[c] + t*(v0[c] + 0.5*t*a0[c]);
                }else{
                    double sum = 0.;
                    for (int m=0; m<s; m++){
                        sum += x[k][m]*source[m][c];
                    }
                    st->var_stage_a[v][k][c] = sum;
                    // (the classical round reads no stage point: the first
                    // forces put them where the round leaves the unknowns)
                    double sum_x = 0.;
                    for (int m=0; !classical && m<s; m++){
                        sum_x += x[k][m]*source_x[m][c];
                    }
                    st->var_stage_x[v][k][c] = sum_x;
                }
            }
        }
    }
    return retry ? PFVI_PREDICTED_RETRY : (extrapolate ? PFVI_PREDICTED_EXTRAPOLATED : PFVI_PREDICTED_NONE);
}


// The classical form's linear structure for the solve (pfvi_solve.c):
// Q^i = q_k + y[i-1] with y[i-1] = c_nu[i] h v_k + h^2 sum_j nu[i][j] w_j A^j,
// so S[i-1][j] = -h^2 nu[i][j] w_j; the forces of stages 1 .. s-2 act within
// the step (nu's last column is zero; stage 0 is the fixed start).
static void classical_form(const struct pfvi_lobatto* rule, double h, struct pfvi_solve_form* f){
    const int s = rule->s, m = s - 1;
    memset(f, 0, sizeof(*f));
    f->classical = 1;
    f->m = m;
    f->k_last = s - 2;
    f->increment = s - 2;
    f->fscale = 1.;
    for (int l=0; l<m; l++){
        for (int k=1; k<=s-2; k++){
            f->S[l][k] = -h*h*rule->nu[l+1][k]*rule->w[k];
        }
    }
    for (int k=1; k<s; k++){
        f->X[k][k-1] = 1.;
    }
}

// A fitted particle's: y = yc - solve F with F_k = h^2 (a_k - the centre's)
// + u2 (d_k - ...), stage k at q_k + (base_k + bbar_k y[0] + y[k] + shift_k)
// inside the step and q_k + (y[0] + shift) at its end.
static void fitted_form(const struct pfvi_lobatto* rule, const struct pfvi_stage_fit* fit, double h,
        struct pfvi_solve_form* f){
    const int s = rule->s, m = s - 1;
    memset(f, 0, sizeof(*f));
    f->m = m;
    f->k_last = s - 1;
    f->increment = 0;
    f->fscale = h*h;
    f->u2 = fit->u2;
    for (int l=0; l<m; l++){
        for (int k=1; k<s; k++){
            f->S[l][k] = fit->solve[l][k];
        }
    }
    for (int k=1; k<s-1; k++){
        f->X[k][0] = fit->bbar[k];
        f->X[k][k] = 1.;
    }
    f->X[s-1][0] = 1.;
}

static int stages_prepare(struct pfvi_state* st, double h){
    if (st->rule.s != st->options.stages){
        // First step, or stages changed (the predictor checks its own s).
        pfvi_stage_rule(st->options.stages, &st->rule, &st->stage_classical);
    }
    if (!(h*h >= DBL_MIN)){
        // The stage equations carry h^2 a: below |h| ~ 1.5e-154 it underflows
        // and the velocity change h a = (h^2 a)/h is lost.
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_UNDERFLOW, .h = h, .n = (size_t)st->rule.s};
        return 0;
    }
    if (st->solve_form_classical_s != st->rule.s || memcmp(&st->solve_form_classical_h, &h, sizeof(h)) != 0){
        classical_form(&st->rule, h, &st->solve_form_classical);
        st->solve_form_classical_s = st->rule.s;
        st->solve_form_classical_h = h;
    }
    return 1;
}

static enum pfvi_fit_status stages_fit(struct pfvi_state* st, size_t i, double omega, double h){
    const int s = st->rule.s;
    if (omega == 0.){
        // u = 0: the classical coefficients, the same at every step (copied
        // only if this particle's fit is not already them).
        if (st->stage_fit_classical[i] != s){
            st->stage_fit[i] = st->stage_classical;
            st->stage_fit_classical[i] = (unsigned char)s;
        }
        st->solve_form[i] = &st->solve_form_classical;
        return PFVI_FIT_OK;
    }
    st->stage_fit_classical[i] = 0;
    const enum pfvi_fit_status status = pfvi_stage_fit(&st->rule, omega, h, st->options.u_max, st->options.fitting,
            &st->stage_fit[i]);
    if (st->stage_fit[i].classical){
        st->solve_form[i] = &st->solve_form_classical;
    }else{
        fitted_form(&st->rule, &st->stage_fit[i], h, &st->solve_forms[i]);
        st->solve_form[i] = &st->solve_forms[i];
    }
    return status;
}

static void stages_copy_fit(struct pfvi_state* st, size_t i, size_t from){
    // (not again if both are the same classical fit already)
    if (st->stage_fit_classical[from] == 0 || st->stage_fit_classical[i] != st->stage_fit_classical[from]){
        st->stage_fit[i] = st->stage_fit[from];
        st->stage_fit_classical[i] = st->stage_fit_classical[from];
    }
    st->solve_form[i] = st->solve_form[from];
}

static double stages_fitted_omega(const struct pfvi_state* st, size_t i){
    return st->stage_fit[i].omega;
}

// collocation[k][j] = integral of l_j over [0, c^k] (the Lobatto IIIA
// matrix): sum_j collocation[k][j] (c^j)^m = (c^k)^(m+1)/(m+1), m < s,
// solved by elimination with partial pivoting on the Vandermonde matrix.
static void collocation_matrix(const struct pfvi_lobatto* rule, double A[PFVI_STAGES_MAX][PFVI_STAGES_MAX]){
    const int s = rule->s;
    double M[PFVI_STAGES_MAX][PFVI_STAGES_MAX], rhs[PFVI_STAGES_MAX][PFVI_STAGES_MAX];
    for (int m=0; m<s; m++){
        for (int j=0; j<s; j++){
            M[m][j] = pow(rule->c[j], m);
        }
        for (int k=0; k<s; k++){
            rhs[m][k] = pow(rule->c[k], m + 1)/(m + 1);
        }
    }
    for (int col=0; col<s; col++){
        int p = col;
        for (int m=col+1; m<s; m++){
            p = (fabs(M[m][col]) > fabs(M[p][col])) ? m : p;
        }
        for (int j=0; j<s; j++){
            const double t = M[col][j]; M[col][j] = M[p][j]; M[p][j] = t;
            const double u = rhs[col][j]; rhs[col][j] = rhs[p][j]; rhs[p][j] = u;
        }
        for (int m=col+1; m<s; m++){
            const double g = M[m][col]/M[col][col];
            for (int j=col; j<s; j++){
                M[m][j] -= g*M[col][j];
            }
            for (int k=0; k<s; k++){
                rhs[m][k] -= g*rhs[col][k];
            }
        }
    }
    for (int k=0; k<s; k++){
        for (int j=s-1; j>=0; j--){
            double sum = rhs[j][k];
            for (int l=j+1; l<s; l++){
                sum -= M[j][l]*A[k][l];
            }
            A[k][j] = sum/M[j][j];
        }
    }
}

// One round of variational particle v's tangent solve: its real particle's
// round (classical or fitted) with the centre frozen at 0.
static void var_round(struct pfvi_state* st, size_t v, int s, double h, const double* hb){
    const struct pfvi_stage_fit* const f = &st->stage_fit[st->var_real[v]];
    if (f->classical){
        classical_round(&st->rule, &st->var_stage_start[v], h, hb, (const double (*)[3])st->var_stage_a[v],
                st->var_unknowns_next[v]);
    }else{
        stage_round(f, &st->var_stage_start[v], &var_centre, s, h, (const double (*)[3])st->var_stage_a[v],
                (const double (*)[3])st->var_stage_x[v], st->var_unknowns_next[v]);
    }
}

// The variational particles' next iterate becomes their current one.
static void var_unknowns_swap(struct pfvi_state* st){
    double (*swap)[PFVI_STAGES_MAX-1][3] = st->var_unknowns;
    st->var_unknowns = st->var_unknowns_next;
    st->var_unknowns_next = swap;
}

// The largest relative change of the variational particles' unknowns in a
// round, measured as the real solve measures its own (a NaN is kept).
static double var_change(const struct pfvi_state* st, int s){
    double change = 0.;
    for (size_t v=0; v<st->var_N; v++){
        const int increment = st->stage_fit[st->var_real[v]].classical ? s - 2 : 0;
        const double relative = pfvi_solve_change((const double (*)[3])st->var_unknowns[v],
                (const double (*)[3])st->var_unknowns_next[v], st->var_stage_start[v].q0, increment, s, 0.);
        change = (relative > change || relative != relative) ? relative : change;
    }
    return change;
}

// Variational particle v's velocity change over the step, from its
// converged tangent stages: the real step's update, centre frozen at 0.
static void var_velocity_change(const struct pfvi_state* st, size_t v, int s, double h, const double* hb,
        double inc_v[3]){
    const struct pfvi_lobatto* const rule = &st->rule;
    const struct pfvi_stage_fit* const f = &st->stage_fit[st->var_real[v]];
    const struct pfvi_stage_start* const ss = &st->var_stage_start[v];
    const double (*y)[3] = st->var_unknowns[v];
    const double (*sa)[3] = st->var_stage_a[v];
    if (f->classical){
        for (int c=0; c<3; c++){
            double sum = 0.;
            for (int j=0; j<s; j++){
                sum += hb[j]*sa[j][c];
            }
            inc_v[c] = sum;
        }
        return;
    }
    const double h2 = h*h;
    double dv[3] = {0., 0., 0.};
    for (int k=0; k<s; k++){
        double qd[3];
        stage_velocity_times_h(f, ss, y, s, k, qd);
        const double wk = rule->w[k], wf = h2*(1. + f->beta_m[k]);
        for (int c=0; c<3; c++){
            if (f->u2 == 0.){
                dv[c] += wk*(f->beta_d[k]*qd[c] + wf*sa[k][c]);
            }else{
                const double d = (k == 0) ? ss->d0[c] : (k == s - 1) ? ss->d0[c] + y[0][c]
                    : (1. + f->beta_m[k])*ss->d0[c] + f->bbar[k]*y[0][c] + y[k][c];
                const double h2a = stage_force_h2(f, ss, &var_centre, h, sa, (const double (*)[3])st->var_stage_x[v], k, c)
                    - f->u2*d;
                dv[c] += wk*(f->beta_d[k]*qd[c] + (1. + f->beta_m[k])*h2a);
            }
        }
    }
    const double gh = f->G*h;
    for (int c=0; c<3; c++){
        inc_v[c] = dv[c]/gh;
    }
}

// The variational particles after the real stage solve converged: their
// tangent solve goes on alone (the real particles at their converged stage
// points, whose stage values are kept) until it too stops; then their end
// state, and MEGNO's increments over the stages. Returns 0 (rolled back,
// fault recorded) if a force evaluation failed.
// It stops by the real solve's rule (pfvi_solve_verdict): once the rate of
// its corrections says the corrected iterate is within the doubles'
// resolution, one final round, whose own change must be at most
// PFVI_SOLVE_CONFIRM, confirms it, and the iterate its forces were
// evaluated at is taken; a change that stops falling is the round-off
// floor (converged if at most PFVI_ITERATION_TOLERANCE). Its equations are
// linear in the variations, but their coefficients are the real stages':
// the real solve's last rounds leave it a round behind.
static int stages_advance_variational(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        const double* hb, double change, double previous, int rounds){
    const struct pfvi_lobatto* const rule = &st->rule;
    const int s = rule->s;
    const size_t nv = st->var_N;
    struct reb_particle* const pv = r->particles_var;
    const uint64_t evaluations = st->statistics.n_force_evaluations;
    int converged = 0, final = 0;
    for (;;){
        // (a change that stops falling at most PFVI_ITERATION_TOLERANCE is
        // the floor at once: the real solve waits a second round there for
        // velocity-dependent forces, which variations never have, and a
        // second-order set's floor can rise and fall by turns above
        // PFVI_SOLVE_CONFIRM, which would never give it two)
        const enum pfvi_solve_next next = pfvi_solve_verdict(change, previous, 0, rounds >= PFVI_ITERATION_MAX);
        if (next == PFVI_SOLVE_CONVERGED || next == PFVI_SOLVE_STALLED || next == PFVI_SOLVE_FAILED
                || next == PFVI_SOLVE_DIVERGING){
            converged = (next == PFVI_SOLVE_CONVERGED || next == PFVI_SOLVE_STALLED);
            break;
        }
        final = final || (next == PFVI_SOLVE_FINAL);
        var_unknowns_swap(st);
        if (!stage_forces(r, st, N, t0, h, 0, 1, s - 1)){
            return 0;
        }
        rounds++;
        for (size_t v=0; v<nv; v++){
            var_round(st, v, s, h, hb);
        }
        if (final){
            const double residual = var_change(st, s);
            if (residual <= PFVI_SOLVE_CONFIRM){
                converged = 1;
                break;
            }
            final = 0;
        }
        previous = change;
        pfvi_newton_correct_variational(st, N);
        change = var_change(st, s);
    }
    st->trial.variational_evaluations = st->statistics.n_force_evaluations - evaluations;
    st->trial.variational_unconverged = !converged;
    st->var_retry_valid = st->retry_allowed;

    // The end state: x from the last stage point, v from p_k+1 (kept in var_dv).
    for (size_t v=0; v<nv; v++){
        double inc_v[3];
        var_velocity_change(st, v, s, h, hb, inc_v);
        const struct reb_particle* const p0 = &st->var_start[v];
        st->var_dv[v] = (struct reb_vec3d){p0->vx + inc_v[0], p0->vy + inc_v[1], p0->vz + inc_v[2]};
    }
    if (r->calculate_megno){
        if (st->collocation_s != s){
            collocation_matrix(rule, st->collocation);
            st->collocation_s = s;
        }
        // ln|delta| of REBOUND's MEGNO set (the first N variational
        // particles) at each stage: the tangent stage points, the velocities
        // of the step's ends and, within, of the collocation polynomial of
        // the stage forces (stage order s; the interpolant's derivative,
        // Lobatto IIIB's stage velocity, has order s - 2).
        double L[PFVI_STAGES_MAX];
        const size_t n_megno = (r->N < nv) ? r->N : nv;
        for (int k=0; k<s; k++){
            double norm2 = 0.;
            for (size_t v=0; v<n_megno; v++){
                const struct reb_particle* const p0 = &st->var_start[v];
                double w[3];
                if (k == 0){
                    w[0] = p0->vx; w[1] = p0->vy; w[2] = p0->vz;
                }else if (k == s - 1){
                    w[0] = st->var_dv[v].x; w[1] = st->var_dv[v].y; w[2] = st->var_dv[v].z;
                }else{
                    double dw[3] = {0., 0., 0.};
                    for (int j=0; j<s; j++){
                        for (int c=0; c<3; c++){
                            dw[c] += st->collocation[k][j]*st->var_stage_a[v][j][c];
                        }
                    }
                    w[0] = p0->vx + h*dw[0]; w[1] = p0->vy + h*dw[1]; w[2] = p0->vz + h*dw[2];
                }
                for (int c=0; c<3; c++){
                    norm2 += st->var_stage_x[v][k][c]*st->var_stage_x[v][k][c] + w[c]*w[c];
                }
            }
            L[k] = 0.5*log(norm2);
        }
        double integral = 0.;
        for (int k=0; k<s; k++){
            integral += rule->w[k]*L[k];
        }
        const double t_rel = t0 - r->megno_initial_t;
        st->trial.megno_dY = megno_increment(t_rel, h, L[0], L[s-1], h*integral);
        // Y at each stage, from ln|delta|'s integral up to it (the collocation
        // rows), and Lobatto's rule over them for <Y>'s integral.
        double Y_integral = 0.;
        for (int k=0; k<s; k++){
            double partial = 0.;
            for (int j=0; j<s; j++){
                partial += st->collocation[k][j]*L[j];
            }
            const double tk = t_rel + rule->c[k]*h;
            const double Ys = r->megno_Ys + ((k == s - 1) ? st->trial.megno_dY
                : megno_increment(t_rel, rule->c[k]*h, L[0], L[k], h*partial));
            Y_integral += rule->w[k]*megno_Y(Ys, tk);
        }
        st->trial.megno_Y_integral = h*Y_integral;
    }
    for (size_t v=0; v<nv; v++){
        double x[3];
        stage_position(&st->stage_fit[st->var_real[v]], &st->var_stage_start[v], &var_compensation, NULL,
                (const double (*)[3])st->var_unknowns[v], s, s - 1, x);
        pv[v].x = x[0]; pv[v].y = x[1]; pv[v].z = x[2];
        pv[v].vx = st->var_dv[v].x; pv[v].vy = st->var_dv[v].y; pv[v].vz = st->var_dv[v].z;
        pv[v].ax = st->var_stage_a[v][s-1][0];
        pv[v].ay = st->var_stage_a[v][s-1][1];
        pv[v].az = st->var_stage_a[v][s-1][2];
    }
    return 1;
}

// One round for every variational particle. Their change for their own
// verdict is the corrected round's (the solve's variational_change): the
// last one becomes the one before.
static void variational_rounds(struct pfvi_state* st, double h, const double* hb){
    const int s = st->rule.s;
    if (st->var_N){
        for (size_t v=0; v<st->var_N; v++){
            var_round(st, v, s, h, hb);
        }
        st->var_solve_previous = st->var_solve_change;
    }
}

// One round for every real and variational particle: unknowns_next from
// the forces at the stage points of unknowns (the variational particles'
// change is measured once the solve has corrected their round, for their
// own verdict: they never enter the real one).
static void stage_rounds(struct pfvi_state* st, size_t N, double h){
    const struct pfvi_lobatto* const rule = &st->rule;
    const int s = rule->s;
    // The classical form's h w_j: the same products in every round and in
    // the update, so that the doubles' step is the IIIA-IIIB pair exactly.
    double hb[PFVI_STAGES_MAX];
    for (int j=0; j<s; j++){
        hb[j] = h*rule->w[j];
    }
    for (size_t i=0; i<N; i++){
        if (st->stage_fit[i].classical){
            classical_round(rule, &st->stage_start[i], h, hb, (const double (*)[3])st->stage_a[i],
                    st->unknowns_next[i]);
        }else{
            stage_round(&st->stage_fit[i], &st->stage_start[i], &st->centre[i], s, h,
                    (const double (*)[3])st->stage_a[i], (const double (*)[3])st->stage_x[i], st->unknowns_next[i]);
        }
    }
    variational_rounds(st, h, hb);
}

static int stage_solve_forces(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h,
        int k_first, int k_last){
    return stage_forces(r, st, N, t0, h, 1, k_first, k_last);
}

// The stage points of the iterate unknowns, for the solve's Jacobians.
static void stage_solve_positions(struct pfvi_state* st, size_t N, double h){
    (void)h;
    const int s = st->rule.s;
    for (size_t i=0; i<N; i++){
        for (int k=1; k<s; k++){
            stage_position(&st->stage_fit[i], &st->stage_start[i], &st->compensation[i], st->end_low[i],
                    (const double (*)[3])st->unknowns[i], s, k, st->solve_x[i][k]);
        }
    }
}

// The classical form's unknowns are its stage points less the start.
static void stage_solve_start_at(struct pfvi_state* st, size_t N){
    const int s = st->rule.s;
    for (size_t i=0; i<N; i++){
        if (!st->stage_fit[i].classical){
            continue;
        }
        const double* const q0 = st->stage_start[i].q0;
        for (int k=1; k<s; k++){
            for (int c=0; c<3; c++){
                st->unknowns[i][k-1][c] = st->solve_x[i][k][c] - q0[c];
            }
        }
    }
}

// The variational particles' change after the solve corrected their round.
static void stage_solve_variational_change(struct pfvi_state* st){
    st->var_solve_change = var_change(st, st->rule.s);
}

static const struct pfvi_solve_ops stage_solve_ops = {
    .forces = stage_solve_forces,
    .round = stage_rounds,
    .positions = stage_solve_positions,
    .start_at = stage_solve_start_at,
    .variational_change = stage_solve_variational_change,
};

// The classical step's velocity increment sum_j hb_j A^j + the carried
// compensation, the sum compensated (Knuth's two-sum) and what its rounding
// lost returned in low, to be carried as the position's end_low is: the s
// terms are of one size where a step turns the velocity, and their plain
// sum's roundings were most of the energy's random walk (Kepler e = 0.99 at
// epsilon 1e-12: the walk's variance 0.69 of the plain sum's;
// docs/roundoff.md). (The three components are lanes, the fourth a copy of
// z; each lane is the scalar operation, so every build gives the same bits.)
PFVI_VECTOR_CLONES
static void velocity_increment(int s, const double* hb, const double (*a)[3], const double carried[3],
        double inc_v[3], double low[3]){
    pfvi_lanes sum = {0., 0., 0., 0.}, lost = {0., 0., 0., 0.};
    for (int j=0; j<s; j++){
        const pfvi_lanes term = (pfvi_lanes){hb[j], hb[j], hb[j], hb[j]}*(pfvi_lanes){a[j][0], a[j][1], a[j][2], a[j][2]};
        const pfvi_lanes next = sum + term, bb = next - sum;
        lost += (sum - (next - bb)) + (term - bb);
        sum = next;
    }
    const pfvi_lanes rest = lost + (pfvi_lanes){carried[0], carried[1], carried[2], carried[2]};
    const pfvi_lanes inc = sum + rest;
    const pfvi_lanes out = (sum - inc) + rest;
    for (int c=0; c<3; c++){
        inc_v[c] = inc[c];
        low[c] = out[c];
    }
}

static enum pfvi_trial stages_advance(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, double h){
    const struct pfvi_lobatto* const rule = &st->rule;
    const int s = rule->s;
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const p0 = st->start;

    const size_t nv = st->var_N;
    for (size_t i=0; i<N; i++){
        stage_start_of(rule, &st->stage_fit[i], &p0[i], &st->centre[i], h, &st->stage_start[i]);
    }
    for (size_t v=0; v<nv; v++){
        stage_start_of(rule, &st->stage_fit[st->var_real[v]], &st->var_start[v], &var_centre, h, &st->var_stage_start[v]);
    }
    // Every real particle in the classical form (no velocity-dependent
    // force): unless this is a retry, the solve's two-body predictor draws
    // their whole first iterate, and their extrapolated stages and round
    // would be overwritten unread (the variational particles' are not).
    int classical = !r->force_is_velocity_dependent;
    for (size_t i=0; classical && i<N; i++){
        classical = st->stage_fit[i].classical;
    }
    const int predicted = stage_predict(st, N, t0, h, classical);
    // The classical form's h w_j: the same products in every round and in
    // the update, so that the doubles' step is the IIIA-IIIB pair exactly.
    double hb[PFVI_STAGES_MAX];
    for (int j=0; j<s; j++){
        hb[j] = h*rule->w[j];
    }

    // The first iterate: one round from the predicted accelerations.
    if (!classical || predicted == PFVI_PREDICTED_RETRY){
        stage_rounds(st, N, h);
        pfvi_solve_swap(st);
    }else if (nv){
        variational_rounds(st, h, hb);
        var_unknowns_swap(st);
    }
    st->var_solve_change = INFINITY;
    st->var_solve_previous = INFINITY;
    const enum pfvi_trial solved = pfvi_solve_stages(r, st, N, t0, h, &stage_solve_ops, predicted);
    if (solved == PFVI_TRIAL_ERROR){
        return PFVI_TRIAL_ERROR;
    }
    const int converged = (solved == PFVI_TRIAL_OK);
    const int rounds = (int)st->trial.rounds;
    // A retry of this step from t0 starts from these stages if they converged.
    st->retry_valid = converged && st->retry_allowed;
    st->retry_t0 = t0;
    st->retry_h = h;
    st->retry_stages = s;
    st->var_retry_valid = 0;
    if (!converged){
        pfvi_roll_back(r, st, N, t0);
        return PFVI_TRIAL_NOT_CONVERGED;
    }

    // p_k+1 from the converged stages; x and v advance by compensated increments.
    const double h2 = h*h;
    for (size_t i=0; i<N; i++){
        const struct pfvi_stage_fit* const f = &st->stage_fit[i];
        struct pfvi_compensation* const comp = &st->compensation[i];
        const double (*y)[3] = st->unknowns[i];
        double x[3], inc_v[3];
        stage_position(f, &st->stage_start[i], comp, st->end_low[i], y, s, s - 1, x);
        if (f->classical){
            // p_k+1 = p_k + sum_j hb_j A^j (IIIB).
            velocity_increment(s, hb, (const double (*)[3])st->stage_a[i], comp->v, inc_v, st->dv_low[i]);
        }else{
            double dv[3] = {0., 0., 0.};
            const struct pfvi_centre* const centre = &st->centre[i];
            const double* const d0 = st->stage_start[i].d0;
            for (int k=0; k<s; k++){
                double qd[3];
                stage_velocity_times_h(f, &st->stage_start[i], y, s, k, qd);
                const double wk = rule->w[k], wf = h2*(1. + f->beta_m[k]);
                for (int c=0; c<3; c++){
                    if (f->u2 == 0.){
                        dv[c] += wk*(f->beta_d[k]*qd[c] + wf*(st->stage_a[i][k][c] - centre->acc[c]));
                    }else{
                        // The harmonic part at the solved stage point, the
                        // residual where it was evaluated: as the solve used them.
                        const double d = (k == 0) ? d0[c] : (k == s - 1) ? d0[c] + y[0][c]
                            : (1. + f->beta_m[k])*d0[c] + f->bbar[k]*y[0][c] + y[k][c];
                        const double h2a = stage_force_h2(f, &st->stage_start[i], centre, h,
                                (const double (*)[3])st->stage_a[i], (const double (*)[3])st->stage_x[i], k, c) - f->u2*d;
                        dv[c] += wk*(f->beta_d[k]*qd[c] + (1. + f->beta_m[k])*h2a);
                    }
                }
            }
            // w_k+1 - w_k, and the centre's velocity change h ac.
            const double gh = f->G*h;
            for (int c=0; c<3; c++){
                inc_v[c] = (dv[c]/gh + h*centre->acc[c]) + comp->v[c];
                st->dv_low[i][c] = 0.;
            }
        }
        ps[i].x = x[0]; ps[i].y = x[1]; ps[i].z = x[2];
        ps[i].vx = p0[i].vx + inc_v[0];
        ps[i].vy = p0[i].vy + inc_v[1];
        ps[i].vz = p0[i].vz + inc_v[2];
        ps[i].ax = st->stage_a[i][s-1][0];
        ps[i].ay = st->stage_a[i][s-1][1];
        ps[i].az = st->stage_a[i][s-1][2];
        // Kept in dv until the step is known to be taken.
        st->dv[i] = (struct reb_vec3d){inc_v[0], inc_v[1], inc_v[2]};
    }
    if (nv && !stages_advance_variational(r, st, N, t0, h, hb, st->var_solve_change, st->var_solve_previous, rounds)){
        return PFVI_TRIAL_ERROR;
    }
    r->t = t0 + h;
    return PFVI_TRIAL_OK;
}

// The step is taken: keep what the sums of x and v lost, and this step's
// stage accelerations for the next step's predictor.
static void stages_commit(struct reb_simulation* r, struct pfvi_state* st, size_t N, double h){
    const struct reb_particle* const ps = r->particles;
    const struct reb_particle* const p0 = st->start;
    for (size_t i=0; i<N; i++){
        struct pfvi_compensation* const comp = &st->compensation[i];
        const double (*y)[3] = st->unknowns[i];
        const struct pfvi_stage_start* const ss = &st->stage_start[i];
        const int s = st->rule.s;
        const struct pfvi_stage_fit* const f = &st->stage_fit[i];
        const double* const low = st->end_low[i];
        comp->x[0] = (stage_increment(f, ss, y, s, 0) + (comp->x[0] + low[0])) - (ps[i].x - p0[i].x);
        comp->x[1] = (stage_increment(f, ss, y, s, 1) + (comp->x[1] + low[1])) - (ps[i].y - p0[i].y);
        comp->x[2] = (stage_increment(f, ss, y, s, 2) + (comp->x[2] + low[2])) - (ps[i].z - p0[i].z);
        const double* const dv_low = st->dv_low[i];
        comp->v[0] = (st->dv[i].x - (ps[i].vx - p0[i].vx)) + dv_low[0];
        comp->v[1] = (st->dv[i].y - (ps[i].vy - p0[i].vy)) + dv_low[1];
        comp->v[2] = (st->dv[i].z - (ps[i].vz - p0[i].vz)) + dv_low[2];
    }
    double (*swap)[PFVI_STAGES_MAX][3] = st->predictor_a;
    st->predictor_a = st->stage_a;
    st->stage_a = swap;
    swap = st->predictor_x;
    st->predictor_x = st->stage_x;
    st->stage_x = swap;
    st->predictor_stages = st->rule.s;
    st->predictor_N = N;
    st->predictor_h = h;
    st->predictor_t = r->t;
    st->retry_valid = 0;  // stage_a now holds the predictor's old buffer
    // The variational particles' stages likewise.
    swap = st->var_predictor_a;
    st->var_predictor_a = st->var_stage_a;
    st->var_stage_a = swap;
    swap = st->var_predictor_x;
    st->var_predictor_x = st->var_stage_x;
    st->var_stage_x = swap;
    st->var_predictor_N = st->var_N;
    st->var_retry_valid = 0;
}

// Half the trace of the step's map for a 1-D particle under a = -W2 d
// about a centre at rest: the stage equations above with that force are
// linear in the unknowns, y + kappa S d(y) = yc with kappa = u^2 - W2 h^2
// (the force the iteration carries, h^2 a + u2 d), solved here directly for
// the start (d, w) = (1, 0) (for x_k+1) and (0, 1) (for w_k+1).
static double stages_half_trace(const struct pfvi_state* st, size_t i, double h, double W2){
    const struct pfvi_stage_fit* const f = &st->stage_fit[i];
    const int s = st->rule.s, m = s - 1;
    const double kappa = f->u2 - W2*h*h;
    // d^k = d0 dk0[k] + sum_j dky[k][j] y_j (stage point k, less the centre).
    double dk0[PFVI_STAGES_MAX], dky[PFVI_STAGES_MAX][PFVI_STAGES_MAX-1] = {{0.}};
    for (int k=0; k<s; k++){
        dk0[k] = (k == 0 || k == m) ? 1. : 1. + f->beta_m[k];
        if (k > 0){
            dky[k][0] = (k == m) ? 1. : f->bbar[k];
        }
        if (k > 0 && k < m){
            dky[k][k] = 1.;
        }
    }
    double A[PFVI_STAGES_MAX-1][PFVI_STAGES_MAX-1];
    double rhs[2][PFVI_STAGES_MAX-1];
    for (int l=0; l<m; l++){
        double forced = 0.;
        for (int j=0; j<m; j++){
            double sum = 0.;
            for (int k=0; k<s; k++){
                sum += f->solve[l][k]*dky[k][j];
            }
            A[l][j] = (l == j) + kappa*sum;
        }
        for (int k=0; k<s; k++){
            forced += f->solve[l][k]*dk0[k];
        }
        rhs[0][l] = -f->start_offset[l] - kappa*forced;  // d0 = 1, w0 = 0
        rhs[1][l] = -f->G*h*f->start_momentum[l];        // d0 = 0, w0 = 1
    }
    // Gaussian elimination with partial pivoting, both right-hand sides.
    for (int k=0; k<m; k++){
        int p = k;
        for (int l=k+1; l<m; l++){
            p = (fabs(A[l][k]) > fabs(A[p][k])) ? l : p;
        }
        for (int j=0; j<m; j++){
            const double tmp = A[k][j]; A[k][j] = A[p][j]; A[p][j] = tmp;
        }
        for (int c=0; c<2; c++){
            const double tmp = rhs[c][k]; rhs[c][k] = rhs[c][p]; rhs[c][p] = tmp;
        }
        if (A[k][k] == 0.){
            return NAN;
        }
        for (int l=k+1; l<m; l++){
            const double g = A[l][k]/A[k][k];
            for (int j=k; j<m; j++){
                A[l][j] -= g*A[k][j];
            }
            rhs[0][l] -= g*rhs[0][k];
            rhs[1][l] -= g*rhs[1][k];
        }
    }
    double y[2][PFVI_STAGES_MAX-1];
    for (int c=0; c<2; c++){
        for (int k=m-1; k>=0; k--){
            double sum = rhs[c][k];
            for (int j=k+1; j<m; j++){
                sum -= A[k][j]*y[c][j];
            }
            y[c][k] = sum/A[k][k];
        }
    }
    // x_k+1 from (1, 0): d0 + y_0. w_k+1 from (0, 1): 1 + dv/(G h), dv as in
    // stages_advance with h^2 a^k = -W2 h^2 d^k.
    double dv = 0.;
    for (int k=0; k<s; k++){
        double qd = f->Bbar[k]*y[1][0], d = 0.;
        for (int l=1; l<m; l++){
            qd += f->a[k][l]*y[1][l];
        }
        for (int j=0; j<m; j++){
            d += dky[k][j]*y[1][j];
        }
        dv += st->rule.w[k]*(f->beta_d[k]*qd - (1. + f->beta_m[k])*W2*h*h*d);
    }
    return 0.5*((1. + y[0][0]) + (1. + dv/(f->G*h)));
}

static void stages_stage_accelerations(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
        double (*a)[3]){
    (void)r;
    for (int k=0; k<st->rule.s; k++){
        for (int c=0; c<3; c++){
            a[k][c] = st->stage_a[i][k][c];
        }
    }
}

static void stages_stage_positions(const struct reb_simulation* r, const struct pfvi_state* st, size_t i,
        double (*x)[3]){
    (void)r;
    for (int k=0; k<st->rule.s; k++){
        for (int c=0; c<3; c++){
            x[k][c] = st->stage_x[i][k][c];
        }
    }
}

const struct pfvi_scheme pfvi_stages_scheme = {
    .prepare = stages_prepare,
    .fit = stages_fit,
    .copy_fit = stages_copy_fit,
    .fitted_omega = stages_fitted_omega,
    .advance = stages_advance,
    .commit = stages_commit,
    .stage_accelerations = stages_stage_accelerations,
    .stage_positions = stages_stage_positions,
    .half_trace = stages_half_trace,
};

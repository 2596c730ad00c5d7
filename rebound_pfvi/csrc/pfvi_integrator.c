/**
 * pfvi_integrator.c: the "pfvi" integrator for REBOUND.
 *
 * A variational integrator built on the phase-fitted discrete Lagrangian of
 * Kosmas & Vlachos, "Phase-fitted Discrete Lagrangian Integrators". This file
 * holds the REBOUND integrator table, its fields, and the step: validation,
 * the position-momentum (discrete Legendre) update of pfvi_fitting.c, and the
 * rollback that leaves the simulation bit-identical when a step is refused.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "pfvi.h"
#include "rebound_internal.h"

static void pfvi_step(struct reb_simulation* r, void* state);
static void pfvi_synchronize(struct reb_simulation* r, void* state);
static void pfvi_did_add_particle(struct reb_simulation* r);
static void pfvi_will_remove_particle(struct reb_simulation* r, size_t index);
static void* pfvi_create(void);
static void pfvi_free(void* state);
static const struct reb_binarydata_field_descriptor pfvi_field_descriptor_list[];

const struct reb_integrator pfvi_integrator = {
    .documentation =
    "PFVI: phase-fitted discrete Lagrangian (variational) integrator of O. T. Kosmas and "
    "D. S. Vlachos, \"Phase-fitted Discrete Lagrangian Integrators\" (below: K&V). The discrete "
    "Lagrangian Ld = h sum_j w_j L(q^j, qdot^j) interpolates each particle's path "
    "with trigonometric functions fitted to a local frequency omega, so that the "
    "harmonic oscillator at omega is integrated exactly. The frequency is either "
    "estimated from the curvature of the orbit, omega = |v x a|/|v|^2 (the angular "
    "rate on the osculating circle), or given. Steps are the position-momentum "
    "form p_k = -D1 Ld, p_k+1 = D2 Ld (Marsden & West 2001, Acta Numerica 10, 357). "
    "With two nodes (stages = 2) the step is explicit and second order, needs one "
    "force evaluation (the acceleration at the end of a step is reused at the start "
    "of the next), and with fitting = 'none' is exactly velocity Verlet. With s = 3 "
    "to 6 Gauss-Lobatto nodes and interior corrections (K&V, 'Increasing the algebraic "
    "order'; Marsden & West 2001, section 2.6) the order is 2s - 2 and each step solves for the stage "
    "points by fixed-point iteration, stopped as in IRKGL16 (Antonana, Makazaga & "
    "Murua 2017, J. Comput. Phys.); a solve that does not converge is refused. "
    "Steps are adaptive by default (epsilon = " PFVI_STR(PFVI_EPSILON_DEFAULT) "): K&V's "
    "osculating-circle bound on the position error ('Frequency Evaluation and Error Control') "
    "sets them, time-symmetrically (step_control = "
    "'reversible') or by accept/reject ('seed'); epsilon = 0 gives fixed steps of sim.dt. "
    "Forward or backward. A step that cannot be taken "
    "(invalid option, non-finite particle or force, overflow, u at a pole) raises an error "
    "and leaves t and every particle bit-identical; if a force callback added or removed "
    "particles during the step, t and every particle still present are restored and the "
    "error says how many were removed or added. Changes of the force model between "
    "integrate() or steps() calls or in a heartbeat act from the next step on, exactly as "
    "a fresh integrate() from that state. Options are checked, by name, when the next step "
    "starts (REBOUND offers no hook on assignment): a bad value makes integrate() raise and "
    "changes nothing. Derivations and measurements: the docs/ folder of rebound_pfvi's source."
    ,
    .step = pfvi_step,
    .synchronize = pfvi_synchronize,
    .create = pfvi_create,
    .free = pfvi_free,
    .did_add_particle = pfvi_did_add_particle,
    .will_remove_particle = pfvi_will_remove_particle,
    .field_descriptor_list = pfvi_field_descriptor_list,
};

static struct reb_binarydata_enum_descriptor pfvi_fitting_enum[] = {
    { PFVI_FITTING_PHASE, "phase" },
    { PFVI_FITTING_PHASE_LITERAL, "phase-literal" },
    { PFVI_FITTING_NONE, "none" },
    { 0 },
};

static struct reb_binarydata_enum_descriptor pfvi_step_control_enum[] = {
    { PFVI_STEP_CONTROL_SEED, "seed" },
    { PFVI_STEP_CONTROL_REVERSIBLE, "reversible" },
    { 0 },
};

static struct reb_binarydata_enum_descriptor pfvi_frequency_enum[] = {
    { PFVI_FREQUENCY_CURVATURE, "curvature" },
    { PFVI_FREQUENCY_FIXED, "fixed" },
    { 0 },
};

#define PFVI_FIELD(doc, dtype, name) \
    { doc, dtype, #name, offsetof(struct pfvi_state, name), 0, 0, 0 }

static const struct reb_binarydata_field_descriptor pfvi_field_descriptor_list[] = {
    { "Fitting of the discrete Lagrangian. 'phase' (default): K&V's phase-fitted "
      "Ld divided by gamma(u) = u cot u, which makes positions and momenta exact on the "
      "harmonic oscillator (two nodes). 'phase-literal': Ld exactly as printed by K&V; positions "
      "are exact on the oscillator but momenta come out scaled by gamma(u). 'none': the "
      "classical trapezoidal Ld of Marsden & West (velocity Verlet), and for stages >= 3 the "
      "classical Lobatto Ld. Type: text (REBOUND lists its storage type). Default 'phase'.",
      REB_INT, "fitting", offsetof(struct pfvi_state, fitting), 0, 0, pfvi_fitting_enum },
    { "Source of the frequency omega. 'curvature' (default): per particle, omega = "
      "|v x a|/|v|^2 at the start of the step, in the simulation frame (K&V, 'Frequency "
      "Evaluation and Error Control'); 0 for a particle at rest or on a straight line. 'fixed': "
      "the field omega, for every particle. Type: text. Default 'curvature'.",
      REB_INT, "frequency", offsetof(struct pfvi_state, frequency), 0, 0, pfvi_frequency_enum },
    PFVI_FIELD("Frequency used when frequency = 'fixed' (code units of 1/time, finite, >= 0). Default 0.",
        REB_DOUBLE, omega),
    PFVI_FIELD("Number s of Gauss-Lobatto nodes of the discrete Lagrangian, an integer from "
        PFVI_STR(PFVI_STAGES_MIN) " to " PFVI_STR(PFVI_STAGES_MAX) "; the order is "
        "2s - 2. s = 2: nodes 0 and 1, an explicit step with one force evaluation; with "
        "'phase' it is unstable for a body whose force ignores its own position (the star in a "
        "centre-of-mass frame: its offset from the origin grows by 1/cos u per step). s = 4 "
        "(default): order 6, stable there. s >= 3: interior corrections delta q^j made stationary "
        "(K&V, 'Increasing the algebraic order'), solved by "
        "fixed-point iteration with s - 1 force evaluations per iteration (s if forces depend "
        "on velocities), at most " PFVI_STR(PFVI_STAGE_MAX_ITERATIONS) " iterations per step. "
        "Default " PFVI_STR(PFVI_STAGES_DEFAULT) ".",
        REB_INT, stages),
    PFVI_FIELD("Largest |u| = omega*|dt| used in the fitted coefficients; a larger value is "
        "limited to u_max and counted in n_u_limited. Must lie in (0, pi). The two-point "
        "coefficients have a pole at u = pi/2 (and, for 'phase-literal', at pi): a step whose "
        "u lies within " PFVI_STR(PFVI_POLE_GUARD) " of one is refused. Default "
        PFVI_STR(PFVI_U_MAX_DEFAULT) ", where tan(u)/u = 1.56. For s >= 3 "
        "the stage matrix is regular on (0, pi) except for s = 4 at u = 2.857; steps where its "
        "determinant falls below " PFVI_STR(PFVI_POLE_GUARD) " of its value at u = 0 are refused.",
        REB_DOUBLE, u_max),
    PFVI_FIELD("Tolerance of the adaptive step control (K&V, 'Frequency Evaluation and Error "
        "Control'): the bound "
        "| |R1 - R2| - |O1 - O2| | on a step's position error from the osculating circles "
        "(radius R, centre O) at its two ends, relative to the smaller radius, for the particle "
        "where it is largest; on non-planar paths the centre's motion out of the circles' mean "
        "plane (torsion, not error) is left out. The estimate is third order in dt whatever the "
        "order of the scheme. A particle without circles at both ends on the same side "
        "of its path (at rest, on a straight or radial path, or across an inflection) is left out of "
        "that step's estimate; with no particle left the step is held, at most sim.dt (so on a "
        "radial path the accuracy is sim.dt's). 0: fixed steps of sim.dt. Default "
        PFVI_STR(PFVI_EPSILON_DEFAULT) ". The "
        "step is also kept at u = omega*|dt| <= u_max. sim.dt is the first step tried and, "
        "after each step, the next one proposed, as with IAS15.",
        REB_DOUBLE, epsilon),
    { "Step selection when epsilon > 0. 'seed': a step is accepted if the estimate "
      "is at most epsilon, otherwise retried shorter (counted in n_rejected, nothing changed); "
      "the next step is h*" PFVI_STR(PFVI_CONTROL_SAFETY) "*(epsilon/estimate)^(1/"
      PFVI_STR(PFVI_CONTROL_ORDER) "), at most " PFVI_STR(PFVI_CONTROL_GROW_MAX) "x and at least "
      PFVI_STR(PFVI_CONTROL_SHRINK_MIN) "x larger; a step rejected " PFVI_STR(PFVI_CONTROL_MAX_REJECTIONS)
      " times is refused. 'reversible' (default): each step solves estimate(start, end) = epsilon (or "
      "u = u_max) for h, and "
      "is fitted to the mean of the curvature frequencies at its two ends, so the step chosen "
      "from either end is the same: time-symmetric, as in Hut, Makino & McMillan 1995 (ApJ 443, "
      "L93). It costs about 3 to 5 trial steps per step (n_attempts). Near pericentre and "
      "apocentre the estimate is not monotonic in h and the two directions may pick different "
      "steps, so a round trip is not exact; energy errors stay bounded where 'seed' drifts. "
      "Type: text. Default 'reversible'.",
      REB_INT, "step_control", offsetof(struct pfvi_state, step_control), 0, 0, pfvi_step_control_enum },
    { "", REB_POINTER, "compensation", offsetof(struct pfvi_state, compensation),
        offsetof(struct pfvi_state, N_compensation), sizeof(struct pfvi_compensation), 0 },
    { "", REB_POINTER, "stage_accelerations", offsetof(struct pfvi_state, predictor_a),
        offsetof(struct pfvi_state, predictor_N), sizeof(*((struct pfvi_state*)0)->predictor_a), 0 },
    { "", REB_DOUBLE, "dt_reversible", offsetof(struct pfvi_state, dt_reversible), 0, 0, 0 },
    { "", REB_INT, "predictor_stages", offsetof(struct pfvi_state, predictor_stages), 0, 0, 0 },
    { "", REB_DOUBLE, "predictor_h", offsetof(struct pfvi_state, predictor_h), 0, 0, 0 },
    { "", REB_DOUBLE, "predictor_t", offsetof(struct pfvi_state, predictor_t), 0, 0, 0 },
    PFVI_FIELD("Statistic: steps taken by this integrator.", REB_UINT64, n_steps),
    PFVI_FIELD("Statistic: particle-steps in which u = omega*dt exceeded u_max and was limited, "
        "or omega exceeded " PFVI_STR(PFVI_OMEGA_MAX) " (omega^2 beyond the doubles) and the particle "
        "was stepped unfitted.",
        REB_UINT64, n_u_limited),
    PFVI_FIELD("Statistic: force evaluations (calls of reb_simulation_update_acceleration). A step "
        "reuses the last step's end acceleration only within one integrate() or steps() call, with no "
        "heartbeat set and nothing the force reads changed (particles, t, G, softening, N_active, "
        "testparticle_type, gravity mode, boundary, additional_forces, extras); otherwise it evaluates "
        "it afresh.",
        REB_UINT64, n_force_evaluations),
    PFVI_FIELD("Statistic: iterations of the stage solve, summed over steps (1 per two-point step).",
        REB_UINT64, n_iterations),
    PFVI_FIELD("Statistic: most iterations of the stage solve in one step.",
        REB_UINT64, iterations_max),
    PFVI_FIELD("Statistic: n_iterations / n_steps.",
        REB_DOUBLE, iterations_mean),
    PFVI_FIELD("Statistic: steps tried and rejected by the step control (or whose stage "
        "solve did not converge and was retried shorter).", REB_UINT64, n_rejected),
    PFVI_FIELD("Statistic: trial steps, taken or not (the work done: n_attempts / n_steps per step).",
        REB_UINT64, n_attempts),
    PFVI_FIELD("Statistic: 'reversible' steps whose step equation was not solved in "
        PFVI_STR(PFVI_REVERSIBLE_MAX_TRIALS) " trial "
        "steps and that were taken at the largest step tried meeting epsilon (not time-symmetric).",
        REB_UINT64, n_asymmetric),
    PFVI_FIELD("Statistic: the step control's error estimate for the last step taken "
        "(0 with fixed steps).", REB_DOUBLE, error_estimate),
    PFVI_FIELD("Statistic: smallest omega used in the last step (after limiting).",
        REB_DOUBLE, omega_min),
    PFVI_FIELD("Statistic: largest omega used in the last step (after limiting).",
        REB_DOUBLE, omega_max),
    { 0 },
};

static void* pfvi_create(void){
    struct pfvi_state* s = calloc(1, sizeof(struct pfvi_state));
    if (!s){
        return NULL;
    }
    s->fitting = PFVI_FITTING_PHASE;
    s->frequency = PFVI_FREQUENCY_CURVATURE;
    s->stages = PFVI_STAGES_DEFAULT;
    s->omega = 0.;
    s->u_max = PFVI_U_MAX_DEFAULT;
    s->epsilon = PFVI_EPSILON_DEFAULT;
    s->step_control = PFVI_STEP_CONTROL_REVERSIBLE;
    return s;
}

static void pfvi_free(void* state){
    struct pfvi_state* s = state;
    if (!s){
        return;
    }
    free(s->start);
    free(s->end);
    free(s->fit);
    free(s->v_rotated);
    free(s->dx);
    free(s->dv);
    free(s->compensation);
    free(s->stage_fit);
    free(s->stage_a);
    free(s->predictor_a);
    free(s->omega_fit);
    free(s->omega_end);
    free(s->osculating_start);
    free(s->unknowns);
    free(s->unknowns_next);
    free(s->origin);
    free(s);
}

// Reports an error through REBOUND; sim.integrate() raises it in Python.
// REBOUND keeps at most 254 characters of a message.
void pfvi_error(struct reb_simulation* r, const char* fmt, ...){
    char msg[REB_STRING_SIZE_MAX];
    va_list args;
    va_start(args, fmt);
    vsnprintf(msg, sizeof(msg), fmt, args);
    va_end(args);
    reb_simulation_error(r, msg);
}

static int pfvi_options_valid(struct reb_simulation* r, const struct pfvi_state* s){
    if (s->fitting != PFVI_FITTING_PHASE && s->fitting != PFVI_FITTING_PHASE_LITERAL
            && s->fitting != PFVI_FITTING_NONE){
        pfvi_error(r, "pfvi: integrator.fitting = %d is not valid; allowed: 'phase', 'phase-literal', 'none'.", s->fitting);
        return 0;
    }
    if (s->frequency != PFVI_FREQUENCY_CURVATURE && s->frequency != PFVI_FREQUENCY_FIXED){
        pfvi_error(r, "pfvi: integrator.frequency = %d is not valid; allowed: 'curvature', 'fixed'.", s->frequency);
        return 0;
    }
    if (s->stages < PFVI_STAGES_MIN || s->stages > PFVI_STAGES_MAX){
        pfvi_error(r, "pfvi: integrator.stages = %d is not supported; allowed: %d to %d.",
                s->stages, PFVI_STAGES_MIN, PFVI_STAGES_MAX);
        return 0;
    }
    if (s->frequency == PFVI_FREQUENCY_FIXED && !(isfinite(s->omega) && s->omega >= 0.)){
        pfvi_error(r, "pfvi: integrator.omega = %g is not valid with frequency 'fixed'; it must be finite and >= 0.", s->omega);
        return 0;
    }
    if (!(s->u_max > 0. && s->u_max < M_PI)){
        pfvi_error(r, "pfvi: integrator.u_max = %g is not valid; it must lie in (0, pi).", s->u_max);
        return 0;
    }
    if (!(isfinite(s->epsilon) && s->epsilon >= 0.)){
        pfvi_error(r, "pfvi: integrator.epsilon = %g is not valid; it must be finite and >= 0 (0: fixed steps of sim.dt).", s->epsilon);
        return 0;
    }
    if (s->step_control != PFVI_STEP_CONTROL_SEED && s->step_control != PFVI_STEP_CONTROL_REVERSIBLE){
        pfvi_error(r, "pfvi: integrator.step_control = %d is not valid; allowed: 'seed', 'reversible'.", s->step_control);
        return 0;
    }
    if (!(isfinite(r->dt) && r->dt != 0.)){
        pfvi_error(r, "pfvi: sim.dt = %g is not valid; the time step must be finite and non-zero.", r->dt);
        return 0;
    }
    if (!isfinite(r->G)){
        pfvi_error(r, "pfvi: sim.G = %g is not finite.", r->G);
        return 0;
    }
    if (!isfinite(r->t)){
        pfvi_error(r, "pfvi: sim.t = %g is not finite.", r->t);
        return 0;
    }
    if (r->N_var){
        pfvi_error(r, "pfvi: variational particles (N_var = %zu) are not supported.", r->N_var);
        return 0;
    }
    return 1;
}

// realloc that keeps the old buffer (and clears *ok) if it fails, so that
// free() still finds every buffer.
static void* pfvi_grow(void* buffer, size_t size, int* ok){
    void* grown = realloc(buffer, size);
    if (!grown){
        *ok = 0;
        return buffer;
    }
    return grown;
}

// Scratch buffers grow only when N does; the hot path allocates nothing.
static int pfvi_ensure_scratch(struct reb_simulation* r, struct pfvi_state* s, size_t N){
    if (s->N_compensation != N){
        // New or removed particles: the low-order parts no longer belong to
        // anyone. (Particles edited in place: pfvi_forget_edited.)
        struct pfvi_compensation* comp = realloc(s->compensation, N*sizeof(struct pfvi_compensation));
        if (!comp){
            pfvi_error(r, "pfvi: could not allocate scratch memory for %zu particles.", N);
            return 0;
        }
        memset(comp, 0, N*sizeof(struct pfvi_compensation));
        s->compensation = comp;
        s->N_compensation = N;
    }
    if (N <= s->N_allocated){
        return 1;
    }
    s->cache_N = 0;
    int ok = 1;
    s->start = pfvi_grow(s->start, N*sizeof(*s->start), &ok);
    s->end = pfvi_grow(s->end, N*sizeof(*s->end), &ok);
    s->fit = pfvi_grow(s->fit, N*sizeof(*s->fit), &ok);
    s->v_rotated = pfvi_grow(s->v_rotated, N*sizeof(*s->v_rotated), &ok);
    s->dx = pfvi_grow(s->dx, N*sizeof(*s->dx), &ok);
    s->dv = pfvi_grow(s->dv, N*sizeof(*s->dv), &ok);
    s->stage_fit = pfvi_grow(s->stage_fit, N*sizeof(*s->stage_fit), &ok);
    s->stage_a = pfvi_grow(s->stage_a, N*sizeof(*s->stage_a), &ok);
    s->predictor_a = pfvi_grow(s->predictor_a, N*sizeof(*s->predictor_a), &ok);
    s->omega_fit = pfvi_grow(s->omega_fit, N*sizeof(*s->omega_fit), &ok);
    s->omega_end = pfvi_grow(s->omega_end, N*sizeof(*s->omega_end), &ok);
    s->osculating_start = pfvi_grow(s->osculating_start, N*sizeof(*s->osculating_start), &ok);
    s->unknowns = pfvi_grow(s->unknowns, N*sizeof(*s->unknowns), &ok);
    s->unknowns_next = pfvi_grow(s->unknowns_next, N*sizeof(*s->unknowns_next), &ok);
    if (s->predictor_N > N){
        // Only after a Simulationarchive load with fewer particles: the buffer
        // now holds N; an archive must never write more than it holds.
        s->predictor_N = 0;
        s->predictor_stages = 0;
    }
    if (!ok){
        pfvi_error(r, "pfvi: could not allocate scratch memory for %zu particles.", N);
        return 0;
    }
    s->N_allocated = N;
    return 1;
}

int pfvi_particle_finite(const struct reb_particle* p){
    return isfinite(p->x) && isfinite(p->y) && isfinite(p->z)
        && isfinite(p->vx) && isfinite(p->vy) && isfinite(p->vz) && isfinite(p->m);
}

static struct pfvi_force_model pfvi_force_model_of(const struct reb_simulation* r){
    struct pfvi_force_model m;
    memset(&m, 0, sizeof(m));
    m.G = r->G;
    m.softening = r->softening;
    m.opening_angle2 = r->opening_angle2;
    m.root_size = r->root_size;
    m.N_root[0] = r->N_root_x; m.N_root[1] = r->N_root_y; m.N_root[2] = r->N_root_z;
    m.OMEGA = r->OMEGA;
    m.OMEGAZ = r->OMEGAZ;
    m.N_active = r->N_active;
    m.gravity = (int)r->gravity;
    m.testparticle_type = r->testparticle_type;
    m.force_is_velocity_dependent = r->force_is_velocity_dependent;
    m.boundary = (int)r->boundary;
    m.N_ghost[0] = r->N_ghost_x; m.N_ghost[1] = r->N_ghost_y; m.N_ghost[2] = r->N_ghost_z;
    m.additional_forces = r->additional_forces;
    m.gravity_custom = r->gravity_custom;
    m.extras = r->extras;
    return m;
}

// Whether the particles, N, t and the force model are, bit for bit, those the
// last step ended with.
static int pfvi_end_is_start(const struct reb_simulation* r, const struct pfvi_state* s){
    const size_t N = r->N;
    if (s->cache_N != N || s->cache_t != r->t){
        return 0;
    }
    const struct pfvi_force_model model = pfvi_force_model_of(r);
    if (memcmp(&model, &s->cache_model, sizeof(model))){
        return 0;
    }
    const struct reb_particle* const ps = r->particles;
    const struct pfvi_end_state* const e = s->end;
    for (size_t i=0; i<N; i++){
        if (memcmp(&ps[i].x, e[i].xv, sizeof(e[i].xv)) || memcmp(&ps[i].m, &e[i].m, sizeof(double))){
            return 0;
        }
    }
    return 1;
}

// A particle the user edited (or replaced) since the last step keeps nothing
// from its predecessor: its compensation is cleared and the stage predictor
// dropped, so that continuing equals starting afresh from the edited state.
static void pfvi_forget_edited(const struct reb_simulation* r, struct pfvi_state* s){
    const size_t N = r->N;
    if (s->cache_N != N || s->N_compensation != N){
        return;  // N changed (compensation already cleared) or no step to compare with
    }
    const struct reb_particle* const ps = r->particles;
    const struct pfvi_end_state* const e = s->end;
    int edited = 0;
    for (size_t i=0; i<N; i++){
        if (memcmp(&ps[i].x, e[i].xv, sizeof(e[i].xv)) || memcmp(&ps[i].m, &e[i].m, sizeof(double))){
            s->compensation[i] = (struct pfvi_compensation){{0., 0., 0.}, {0., 0., 0.}};
            edited = 1;
        }
    }
    if (edited){
        s->predictor_stages = 0;
    }
}

// Puts every particle (all fields) and t back to the start of the step.
void pfvi_roll_back(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0){
    memcpy(r->particles, s->start, N*sizeof(struct reb_particle));
    r->t = t0;
    s->cache_N = 0;
}

// REBOUND synchronizes at the end of steps() and integrate() and around
// pre- and post-timestep modifications: user code may run next and change
// what the force depends on where no field shows it (a callback's own
// variables, REBOUNDx parameters), so the next step evaluates its start force
// afresh, as a new integrate() would.
static void pfvi_synchronize(struct reb_simulation* r, void* state){
    (void)r;
    struct pfvi_state* const s = state;
    if (s){
        s->cache_N = 0;
    }
}

enum { PFVI_STEP_IDLE = 0, PFVI_STEP_RUNNING = 1, PFVI_STEP_TRACKING = 2, PFVI_STEP_UNTRACKED = 3 };

// Room for n entries of origin. Only a callback that adds or removes
// particles during a step gets here, never the hot path.
static int pfvi_origin_reserve(struct pfvi_state* s, size_t n){
    if (n <= s->origin_allocated){
        return 1;
    }
    size_t* const grown = realloc(s->origin, n*sizeof(*grown));
    if (!grown){
        s->in_step = PFVI_STEP_UNTRACKED;
        return 0;
    }
    s->origin = grown;
    s->origin_allocated = n;
    return 1;
}

// The state to track a change of N in, if a step is running: at the first
// change, origin becomes the identity over the step's particles.
static struct pfvi_state* pfvi_origin_tracking(struct reb_simulation* r){
    struct pfvi_state* const s = r->integrator.state;
    if (!s || s->in_step == PFVI_STEP_IDLE || s->in_step == PFVI_STEP_UNTRACKED){
        return NULL;
    }
    if (s->in_step == PFVI_STEP_RUNNING){
        if (!pfvi_origin_reserve(s, s->step_N + 1)){
            return NULL;
        }
        for (size_t i=0; i<s->step_N; i++){
            s->origin[i] = i;
        }
        s->origin_N = s->step_N;
        s->in_step = PFVI_STEP_TRACKING;
    }
    return s;
}

static void pfvi_did_add_particle(struct reb_simulation* r){
    struct pfvi_state* const s = pfvi_origin_tracking(r);
    if (s && pfvi_origin_reserve(s, s->origin_N + 1)){
        s->origin[s->origin_N++] = SIZE_MAX;  // REBOUND appends
    }
}

static void pfvi_will_remove_particle(struct reb_simulation* r, size_t index){
    struct pfvi_state* const s = pfvi_origin_tracking(r);
    if (s && index < s->origin_N){  // REBOUND refuses an index out of range
        memmove(&s->origin[index], &s->origin[index + 1], (s->origin_N - index - 1)*sizeof(*s->origin));
        s->origin_N--;
    }
}

// A callback added or removed particles during a force evaluation: t and
// every particle still there go back to the step's start; the removed ones
// are gone and the added ones stay as added (the callback's doing).
static void pfvi_roll_back_changed_N(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0){
    const size_t now = r->N;
    const double t = r->t;
    r->t = t0;
    s->cache_N = 0;
    if (s->in_step != PFVI_STEP_TRACKING || s->origin_N != now){
        pfvi_error(r, "pfvi: a callback changed the number of particles from %zu to %zu during the force "
                "evaluation at t = %.17g; step not taken, t restored, but the particles could not be "
                "(out of memory): they are left mid-step.", N, now, t);
        return;
    }
    size_t kept = 0, added = 0;
    for (size_t k=0; k<now; k++){
        if (s->origin[k] == SIZE_MAX){
            added++;
        }else{
            r->particles[k] = s->start[s->origin[k]];
            kept++;
        }
    }
    pfvi_error(r, "pfvi: a callback changed the number of particles from %zu to %zu during the force "
            "evaluation at t = %.17g; step not taken: t and the %zu particles still present are restored "
            "to the step's start, %zu removed are gone, %zu added are kept.", N, now, t, kept, N - kept, added);
}

// Evaluates forces through REBOUND, so that every gravity mode, additional
// forces (REBOUNDx) and test particles are handled there. Returns 0, having
// rolled back, if the forces are not finite or a callback changed N.
int pfvi_update_acceleration(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0){
    reb_simulation_update_acceleration(r);
    s->n_force_evaluations++;
    if (r->N != N){
        pfvi_roll_back_changed_N(r, s, N, t0);
        return 0;
    }
    const struct reb_particle* const ps = r->particles;
    for (size_t i=0; i<N; i++){
        if (!(isfinite(ps[i].ax) && isfinite(ps[i].ay) && isfinite(ps[i].az))){
            const double t = r->t;
            // A position or velocity that overflowed in the step is the cause
            // to name, not the force it produced.
            size_t j = 0;
            while (j < N && pfvi_particle_finite(&ps[j])){
                j++;
            }
            const int position = (j < N) && !(isfinite(ps[j].x) && isfinite(ps[j].y) && isfinite(ps[j].z));
            pfvi_roll_back(r, s, N, t0);
            if (j < N){
                pfvi_error(r, "pfvi: particle %zu's %s overflowed (not finite) within the step from t = %.17g; "
                        "step not taken, state restored. Lower dt (or u_max).", j, position ? "position" : "velocity", t0);
            }else{
                pfvi_error(r, "pfvi: the force on particle %zu is not finite at t = %.17g (two particles at one "
                        "position? an additional force returning NaN or Inf?); step not taken, state restored.", i, t);
            }
            return 0;
        }
    }
    return 1;
}

// Implicit final kick for velocity-dependent forces: v = vr + k (a(q, v) + omega^2 q),
// by fixed-point iteration until the change reaches round-off or stops decreasing there.
static int pfvi_final_kick_velocity_dependent(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0){
    struct reb_particle* const ps = r->particles;
    const struct pfvi_two_point* const fit = s->fit;
    double previous = INFINITY;
    for (int iteration=0; iteration<PFVI_VDEP_MAX_ITERATIONS; iteration++){
        double change = 0., scale = 0.;
        for (size_t i=0; i<N; i++){
            const double w2 = fit[i].omega*fit[i].omega;
            const double k = fit[i].half_kick;
            const double vx = s->v_rotated[i].x + k*(ps[i].ax + w2*ps[i].x);
            const double vy = s->v_rotated[i].y + k*(ps[i].ay + w2*ps[i].y);
            const double vz = s->v_rotated[i].z + k*(ps[i].az + w2*ps[i].z);
            change = fmax(change, fmax(fabs(vx - ps[i].vx), fmax(fabs(vy - ps[i].vy), fabs(vz - ps[i].vz))));
            scale = fmax(scale, fmax(fabs(vx), fmax(fabs(vy), fabs(vz))));
            ps[i].vx = vx; ps[i].vy = vy; ps[i].vz = vz;
        }
        const double relative = (scale > 0.) ? change/scale : change;
        if (relative <= 4.*DBL_EPSILON || (relative >= previous && previous < 1e-10)){
            return 1;
        }
        if (relative >= previous){
            break; // diverging
        }
        previous = relative;
        if (!pfvi_update_acceleration(r, s, N, t0)){
            return 0;
        }
    }
    pfvi_roll_back(r, s, N, t0);
    pfvi_error(r, "pfvi: the implicit kick for the velocity-dependent force did not converge; step not taken, state restored.");
    return 0;
}

// The two-point step (stages = 2): explicit, with the closed form of
// pfvi_fitting.c. Commits nothing: see pfvi_two_point_commit.
static enum pfvi_trial pfvi_two_point_trial(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double h){
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const p0 = s->start;
    struct pfvi_end_state* const e = s->end;

    // Fit every particle before anything is written, so that a refusal is cheap.
    const int literal = (s->fitting == PFVI_FITTING_PHASE_LITERAL);
    uint64_t n_limited = 0;
    double omega_min = INFINITY, omega_max = 0.;
    for (size_t i=0; i<N; i++){
        const double omega = s->omega_fit[i];
        const enum pfvi_fit_status status = pfvi_two_point_fit(omega, h, s->u_max, literal, &s->fit[i]);
        if (status == PFVI_FIT_POLE){
            pfvi_roll_back(r, s, N, t0);
            pfvi_error(r, "pfvi: particle %zu: u = omega*dt = %.6g is within %g of a pole of the two-point "
                    "coefficients (cos u = 0 or sin u = 0); step not taken. Lower u_max or dt.",
                    i, omega*h, PFVI_POLE_GUARD);
            return PFVI_TRIAL_ERROR;
        }
        n_limited += (status == PFVI_FIT_LIMITED);
        omega_min = (s->fit[i].omega < omega_min) ? s->fit[i].omega : omega_min;
        omega_max = (s->fit[i].omega > omega_max) ? s->fit[i].omega : omega_max;
    }

    // Kick with the residual force, then rotate with the harmonic flow. With
    // cos u > 0 (always at the default u_max) the whole step is an increment
    // of x and v, added with compensated summation; "phase-literal" and
    // cos u < 0 use plain products and drop the carried low-order parts.
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const q = &p0[i];
        const double* const a = e[i].a;
        const struct pfvi_two_point* const f = &s->fit[i];
        const struct pfvi_compensation* const comp = &s->compensation[i];
        const double w2 = f->omega*f->omega;
        const double kick_x = f->half_kick*(a[0] + w2*q->x);
        const double kick_y = f->half_kick*(a[1] + w2*q->y);
        const double kick_z = f->half_kick*(a[2] + w2*q->z);
        const double k = f->keep, rc = f->cos_u_m_keep;
        if (!literal && k == 1.){
            const double vx = q->vx + kick_x, vy = q->vy + kick_y, vz = q->vz + kick_z;
            s->dx[i] = (struct reb_vec3d){
                (rc*q->x + f->h_sinc_u*vx) + comp->x[0],
                (rc*q->y + f->h_sinc_u*vy) + comp->x[1],
                (rc*q->z + f->h_sinc_u*vz) + comp->x[2]};
            s->dv[i] = (struct reb_vec3d){
                kick_x + (rc*vx - f->omega_sin_u*q->x) + comp->v[0],
                kick_y + (rc*vy - f->omega_sin_u*q->y) + comp->v[1],
                kick_z + (rc*vz - f->omega_sin_u*q->z) + comp->v[2]};
            ps[i].x = q->x + s->dx[i].x;
            ps[i].y = q->y + s->dx[i].y;
            ps[i].z = q->z + s->dx[i].z;
            ps[i].vx = q->vx + s->dv[i].x;
            ps[i].vy = q->vy + s->dv[i].y;
            ps[i].vz = q->vz + s->dv[i].z;
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
    if (!pfvi_update_acceleration(r, s, N, t0)){
        return PFVI_TRIAL_ERROR;
    }
    // Final kick; implicit only if the force depends on velocities.
    if (r->force_is_velocity_dependent){
        for (size_t i=0; i<N; i++){
            s->v_rotated[i] = (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
        }
        if (!pfvi_final_kick_velocity_dependent(r, s, N, t0)){
            return PFVI_TRIAL_ERROR;
        }
    }
    for (size_t i=0; i<N; i++){
        const struct pfvi_two_point* const f = &s->fit[i];
        const double w2 = f->omega*f->omega;
        const double kick_x = f->half_kick*(ps[i].ax + w2*ps[i].x);
        const double kick_y = f->half_kick*(ps[i].ay + w2*ps[i].y);
        const double kick_z = f->half_kick*(ps[i].az + w2*ps[i].z);
        if (compensated && f->keep == 1.){
            s->dv[i].x += kick_x; s->dv[i].y += kick_y; s->dv[i].z += kick_z;
            ps[i].vx = p0[i].vx + s->dv[i].x;
            ps[i].vy = p0[i].vy + s->dv[i].y;
            ps[i].vz = p0[i].vz + s->dv[i].z;
        }else{
            const struct reb_vec3d vr = r->force_is_velocity_dependent ? s->v_rotated[i]
                : (struct reb_vec3d){ps[i].vx, ps[i].vy, ps[i].vz};
            const double g = literal ? f->gamma : 1.;
            ps[i].vx = g*(vr.x + kick_x);
            ps[i].vy = g*(vr.y + kick_y);
            ps[i].vz = g*(vr.z + kick_z);
        }
    }
    for (size_t i=0; i<N; i++){
        if (!pfvi_particle_finite(&ps[i])){
            pfvi_roll_back(r, s, N, t0);
            pfvi_error(r, "pfvi: particle %zu became non-finite in the step from t = %.17g; step not taken, state restored.", i, t0);
            return PFVI_TRIAL_ERROR;
        }
    }
    s->trial_n_limited = n_limited;
    s->trial_omega_min = omega_min;
    s->trial_omega_max = omega_max;
    s->trial_rounds = 1;
    return PFVI_TRIAL_OK;
}

// The step is taken: keep what the sums of x and v lost.
static void pfvi_two_point_commit(struct reb_simulation* r, struct pfvi_state* s, size_t N){
    const struct reb_particle* const ps = r->particles;
    const struct reb_particle* const p0 = s->start;
    const int compensated = (s->fitting != PFVI_FITTING_PHASE_LITERAL);
    for (size_t i=0; i<N; i++){
        struct pfvi_compensation* const comp = &s->compensation[i];
        if (compensated && s->fit[i].keep == 1.){
            comp->x[0] = s->dx[i].x - (ps[i].x - p0[i].x);
            comp->x[1] = s->dx[i].y - (ps[i].y - p0[i].y);
            comp->x[2] = s->dx[i].z - (ps[i].z - p0[i].z);
            comp->v[0] = s->dv[i].x - (ps[i].vx - p0[i].vx);
            comp->v[1] = s->dv[i].y - (ps[i].vy - p0[i].vy);
            comp->v[2] = s->dv[i].z - (ps[i].vz - p0[i].vz);
        }else{
            *comp = (struct pfvi_compensation){{0., 0., 0.}, {0., 0., 0.}};
        }
    }
    s->n_iterations++;
    s->iterations_max = (s->iterations_max < 1) ? 1 : s->iterations_max;
    s->predictor_stages = 0;
}

enum pfvi_trial pfvi_trial_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double t0, double h){
    s->n_attempts++;
    return (s->stages == 2) ? pfvi_two_point_trial(r, s, N, t0, h) : pfvi_stages_trial(r, s, N, t0, h);
}

void pfvi_commit_step(struct reb_simulation* r, struct pfvi_state* s, size_t N, double h){
    if (s->stages == 2){
        pfvi_two_point_commit(r, s, N);
    }else{
        pfvi_stages_commit(r, s, N, h);
    }
    s->n_u_limited += s->trial_n_limited;
    s->omega_min = s->trial_omega_min;
    s->omega_max = s->trial_omega_max;
}

static void pfvi_step_take(struct reb_simulation* r, struct pfvi_state* s){
    if (!pfvi_options_valid(r, s)){
        return;
    }
    const double t0 = r->t;
    const size_t N = r->N;
    if (N == 0){
        if (t0 + r->dt == t0){
            pfvi_error(r, "pfvi: the step dt = %.3g does not change t = %.17g (it is below the rounding of t); "
                    "step not taken.", r->dt, t0);
            return;
        }
        r->t = t0 + r->dt;
        r->dt_last_done = r->dt;
        s->n_steps++;
        return;
    }
    if (!pfvi_ensure_scratch(r, s, N)){
        return;
    }
    r->gravity_ignore_terms = REB_GRAVITY_IGNORE_TERMS_NONE;
    struct reb_particle* const ps = r->particles;
    struct reb_particle* const p0 = s->start;
    struct pfvi_end_state* const e = s->end;

    // e[i].a becomes the acceleration at the start of this step. It is kept
    // from the last step unless anything may have changed the forces: a new
    // integrate() or steps() call (REBOUND resets dt_last_done to 0, or
    // synchronizes at the end of the last), a heartbeat (it may change
    // anything), velocity-dependent forces, or any bit of N, t, the force
    // model (pfvi_force_model_of), a position, velocity or mass.
    const int reuse = r->dt_last_done != 0. && !r->force_is_velocity_dependent && !r->heartbeat
        && pfvi_end_is_start(r, s);
    if (!reuse){
        // Checked before anything is changed, so that a refusal leaves the
        // integrator's own state as it was too.
        for (size_t i=0; i<N; i++){
            if (!pfvi_particle_finite(&ps[i])){
                pfvi_error(r, "pfvi: particle %zu has a non-finite position, velocity or mass; step not taken.", i);
                return;
            }
            if (ps[i].m < 0.){
                pfvi_error(r, "pfvi: particle %zu has a negative mass m = %.17g; masses must be >= 0. Step not taken.", i, ps[i].m);
                return;
            }
        }
        pfvi_forget_edited(r, s);
    }
    s->cache_N = 0;
    memcpy(p0, ps, N*sizeof(struct reb_particle));
    if (!reuse){
        if (!pfvi_update_acceleration(r, s, N, t0)){
            return;
        }
        for (size_t i=0; i<N; i++){
            e[i].a[0] = ps[i].ax; e[i].a[1] = ps[i].ay; e[i].a[2] = ps[i].az;
        }
    }
    for (size_t i=0; i<N; i++){
        s->omega_fit[i] = pfvi_step_frequency(s, &p0[i], e[i].a);
        if (isnan(s->omega_fit[i])){
            pfvi_roll_back(r, s, N, t0);
            pfvi_error(r, "pfvi: particle %zu: its curvature frequency |v x a|/|v|^2 is not a number at t = %.17g; "
                    "step not taken, state restored.", i, t0);
            return;
        }
    }

    double h;
    if (s->epsilon == 0.){
        h = r->dt;
        const enum pfvi_trial trial = pfvi_trial_step(r, s, N, t0, h);
        if (trial == PFVI_TRIAL_NOT_CONVERGED){
            pfvi_error(r, "pfvi: the %d-stage solve did not converge (relative change %.3g after %d iterations) "
                    "in the step from t = %.17g; step not taken, state restored. Lower dt.",
                    s->stages, s->trial_change, (int)s->trial_rounds, t0);
        }
        if (trial != PFVI_TRIAL_OK){
            return;
        }
        pfvi_commit_step(r, s, N, h);
    }else{
        h = pfvi_controlled_step(r, s, N, t0);
        if (h == 0.){
            return;
        }
    }
    if (r->t == t0){
        // t + h rounds to t: REBOUND would call this step for ever.
        pfvi_roll_back(r, s, N, t0);
        pfvi_error(r, "pfvi: the step dt = %.3g does not change t = %.17g (it is below the rounding of t); "
                "step not taken, state restored. Use a larger dt, or start t nearer 0.", h, t0);
        return;
    }
    r->dt_last_done = h;
    s->n_steps++;
    s->iterations_mean = (double)s->n_iterations/(double)s->n_steps;
    // The end of this step is the start of the next.
    for (size_t i=0; i<N; i++){
        memcpy(e[i].xv, &ps[i].x, sizeof(e[i].xv));
        e[i].m = ps[i].m;
        e[i].a[0] = ps[i].ax; e[i].a[1] = ps[i].ay; e[i].a[2] = ps[i].az;
    }
    s->cache_N = N;
    s->cache_t = r->t;
    s->cache_model = pfvi_force_model_of(r);
}

static void pfvi_step(struct reb_simulation* r, void* state){
    struct pfvi_state* const s = state;
    if (!s){
        reb_simulation_error(r, "pfvi: integrator state missing (allocation failed).");
        return;
    }
    s->in_step = PFVI_STEP_RUNNING;
    s->step_N = r->N;
    pfvi_step_take(r, s);
    s->in_step = PFVI_STEP_IDLE;
}

int pfvi_register(void){
    // REBOUND 5.2.2 hangs on a second custom registration in one process, and
    // refuses a duplicate name only after that loop: look the name up first.
    static int registered = 0;
    if (registered){
        return 0;
    }
    char** names = reb_integrators_registered();
    int found = 0;
    for (size_t i=0; names && names[i]; i++){
        if (strcmp(names[i], PFVI_NAME) == 0){
            found = 1;
        }
    }
    free(names);
    registered = 1;
    if (found){
        return 0;
    }
    reb_integrator_register(pfvi_integrator, PFVI_NAME);
    return 1;
}

const char* pfvi_rebound_version_compiled(void){
    return PFVI_REBOUND_VERSION;
}

size_t pfvi_sizeof_simulation(void){
    return sizeof(struct reb_simulation);
}

size_t pfvi_sizeof_particle(void){
    return sizeof(struct reb_particle);
}

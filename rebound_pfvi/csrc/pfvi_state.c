/**
 * pfvi_state.c: what every layer of a step shares: the scratch (grown only
 * with N), the force evaluation through REBOUND and the reuse of the last
 * step's end acceleration, the rollback that leaves a refused step without a
 * trace, the tracking of particles a callback adds or removes mid-step, the
 * faults the glue reports, and the one stopping rule of the fixed-point
 * iterations.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "pfvi.h"
#include "boundary.h"

void pfvi_state_free(struct pfvi_state* st){
    free(st->replay);
    free(st->contact_bodies);
    free(st->contact_order);
    free(st->contact_compensation);
    free(st->start);
    free(st->end);
    free(st->fit);
    free(st->v_rotated);
    free(st->written);
    free(st->dx);
    free(st->end_low);
    free(st->dv);
    free(st->dv_low);
    free(st->compensation);
    free(st->stage_fit);
    free(st->stage_fit_classical);
    free(st->field_blocks);
    free(st->stage_a);
    free(st->predictor_a);
    free(st->stage_x);
    free(st->gravity_x);
    free(st->gravity_a);
    free(st->beside_a);
    free(st->predictor_x);
    free(st->omega_fit);
    free(st->centre);
    free(st->partners);
    free(st->partners_start);
    free(st->partners_scratch);
    free(st->images);
    free(st->omega_end);
    free(st->osculating_start);
    free(st->unknowns);
    free(st->unknowns_next);
    free(st->velocities);
    free(st->stage_start);
    free(st->solve_form);
    free(st->solve_forms);
    free(st->solve_x);
    free(st->newton);
    free(st->newton_order);
    free(st->newton_index);
    free(st->newton_mark);
    free(st->solve_scale);
    free(st->origin);
    free(st->var_real);
    free(st->var_sets);
    free(st->var_start);
    free(st->var_end);
    free(st->var_stage_a);
    free(st->var_predictor_a);
    free(st->var_stage_x);
    free(st->written_var);
    free(st->var_gravity_x);
    free(st->var_gravity_a);
    free(st->var_predictor_x);
    free(st->var_unknowns);
    free(st->var_unknowns_next);
    free(st->var_stage_start);
    free(st->var_dv);
    free(st->output_real);
    free(st->output_shown);
    free(st->output_check);
    free(st->output_var_real);
    free(st->output_var_shown);
    free(st);
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

// The smaller of two lengths: what a buffer holds after a growth that may
// have failed part way (each buffer then its old length or n).
static size_t length_after(int ok, size_t old, size_t n){
    return ok ? n : ((old < n) ? old : n);
}

// The counts of the last step's stages and end, after a load or copy: at
// most what the snapshot's buffers hold, or those buffers' lengths where
// an older build saved no counts (its buffers were saved at them).
static void counts_of_snapshot(struct pfvi_state* st){
    if (!st->counts_saved){
        st->predictor_N = st->predictor_length;
        st->var_predictor_N = st->var_predictor_length;
        st->end_saved_N = st->end_length;
        st->counts_saved = 1;
    }
    st->predictor_N = (st->predictor_N <= st->predictor_length) ? st->predictor_N : 0;
    st->var_predictor_N = (st->var_predictor_N <= st->var_predictor_length) ? st->var_predictor_N : 0;
    st->end_saved_N = (st->end_saved_N <= st->end_length) ? st->end_saved_N : 0;
}

int pfvi_scratch(struct pfvi_state* st, size_t N){
    counts_of_snapshot(st);
    if (st->N_compensation != N){
        // New or removed particles: the low-order parts no longer belong to
        // anyone. (Particles edited in place: pfvi_forget_edited.)
        struct pfvi_compensation* comp = realloc(st->compensation, N*sizeof(struct pfvi_compensation));
        if (!comp){
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_MEMORY, .n = N};
            return 0;
        }
        memset(comp, 0, N*sizeof(struct pfvi_compensation));
        st->compensation = comp;
        st->N_compensation = N;
        st->rho = 0.;  // the symmetric step's density described the old particles
        st->density_scale = 1.;
        st->density_N = 0;
        st->end_N = 0;
        st->end_saved_N = 0;
        st->output_resized = st->output_resized || st->output_N != 0;   // (glue_entry: an edit at an output)
        st->output_N = 0;  // a shown output described the old particles
    }
    if (N <= st->N_allocated){
        return 1;
    }
    st->cache_N = 0;
    int ok = 1;
    st->start = pfvi_grow(st->start, N*sizeof(*st->start), &ok);
    st->end = pfvi_grow(st->end, N*sizeof(*st->end), &ok);
    st->fit = pfvi_grow(st->fit, N*sizeof(*st->fit), &ok);
    st->v_rotated = pfvi_grow(st->v_rotated, N*sizeof(*st->v_rotated), &ok);
    st->written = pfvi_grow(st->written, N*sizeof(*st->written), &ok);
    st->dx = pfvi_grow(st->dx, N*sizeof(*st->dx), &ok);
    st->end_low = pfvi_grow(st->end_low, N*sizeof(*st->end_low), &ok);
    st->dv = pfvi_grow(st->dv, N*sizeof(*st->dv), &ok);
    st->dv_low = pfvi_grow(st->dv_low, N*sizeof(*st->dv_low), &ok);
    st->stage_fit = pfvi_grow(st->stage_fit, N*sizeof(*st->stage_fit), &ok);
    st->stage_fit_classical = pfvi_grow(st->stage_fit_classical, N*sizeof(*st->stage_fit_classical), &ok);
    st->stage_a = pfvi_grow(st->stage_a, N*sizeof(*st->stage_a), &ok);
    st->predictor_a = pfvi_grow(st->predictor_a, N*sizeof(*st->predictor_a), &ok);
    st->stage_x = pfvi_grow(st->stage_x, N*sizeof(*st->stage_x), &ok);
    st->predictor_x = pfvi_grow(st->predictor_x, N*sizeof(*st->predictor_x), &ok);
    st->gravity_x = pfvi_grow(st->gravity_x, N*sizeof(*st->gravity_x), &ok);
    st->gravity_a = pfvi_grow(st->gravity_a, N*sizeof(*st->gravity_a), &ok);
    st->beside_a = pfvi_grow(st->beside_a, N*sizeof(*st->beside_a), &ok);
    st->omega_fit = pfvi_grow(st->omega_fit, N*sizeof(*st->omega_fit), &ok);
    st->centre = pfvi_grow(st->centre, N*sizeof(*st->centre), &ok);
    st->partners = pfvi_grow(st->partners, N*sizeof(*st->partners), &ok);
    st->partners_start = pfvi_grow(st->partners_start, N*sizeof(*st->partners_start), &ok);
    st->partners_scratch = pfvi_grow(st->partners_scratch, N*sizeof(*st->partners_scratch), &ok);
    st->omega_end = pfvi_grow(st->omega_end, N*sizeof(*st->omega_end), &ok);
    st->osculating_start = pfvi_grow(st->osculating_start, N*sizeof(*st->osculating_start), &ok);
    st->unknowns = pfvi_grow(st->unknowns, N*sizeof(*st->unknowns), &ok);
    st->unknowns_next = pfvi_grow(st->unknowns_next, N*sizeof(*st->unknowns_next), &ok);
    st->velocities = pfvi_grow(st->velocities, N*sizeof(*st->velocities), &ok);
    st->stage_start = pfvi_grow(st->stage_start, N*sizeof(*st->stage_start), &ok);
    st->solve_form = pfvi_grow(st->solve_form, N*sizeof(*st->solve_form), &ok);
    st->solve_forms = pfvi_grow(st->solve_forms, N*sizeof(*st->solve_forms), &ok);
    st->solve_x = pfvi_grow(st->solve_x, N*sizeof(*st->solve_x), &ok);
    st->newton = pfvi_grow(st->newton, N*sizeof(*st->newton), &ok);
    st->newton_order = pfvi_grow(st->newton_order, N*sizeof(*st->newton_order), &ok);
    st->newton_index = pfvi_grow(st->newton_index, N*sizeof(*st->newton_index), &ok);
    st->newton_mark = pfvi_grow(st->newton_mark, N*sizeof(*st->newton_mark), &ok);
    st->solve_scale = pfvi_grow(st->solve_scale, N*sizeof(*st->solve_scale), &ok);
    st->output_real = pfvi_grow(st->output_real, N*sizeof(*st->output_real), &ok);
    st->output_shown = pfvi_grow(st->output_shown, N*sizeof(*st->output_shown), &ok);
    // (archives write output_check_N entries, which only a shown output
    // sets: a simulation loaded with fewer particles than its last output
    // had keeps room for them; the sanitizers caught a save reading past a
    // buffer shrunk to N)
    const size_t n_check = (st->output_check_N > N) ? st->output_check_N : N;
    st->output_check = pfvi_grow(st->output_check, n_check*sizeof(*st->output_check), &ok);
    st->output_saved_N = length_after(ok, st->output_saved_N, N);
    st->predictor_length = length_after(ok, st->predictor_length, N);
    st->end_length = length_after(ok, st->end_length, N);
    if (st->output_N > N){
        st->output_N = 0;  // as the predictor's, after an archive with fewer particles
    }
    if (st->predictor_N > N){
        // Only after a Simulationarchive load with fewer particles: the buffer
        // now holds N; an archive must never write more than it holds.
        st->predictor_N = 0;
        st->predictor_stages = 0;
    }
    if (!ok){
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_MEMORY, .n = N};
        return 0;
    }
    memset(st->stage_fit_classical, 0, N*sizeof(*st->stage_fit_classical));   // (what the fits hold is not known)
    st->N_allocated = N;
    return 1;
}

// The contact search's scratch (pfvi_contact.c), grown with N.
int pfvi_contact_scratch(struct pfvi_state* st, size_t N){
    if (N <= st->contact_allocated){
        return 1;
    }
    struct pfvi_contact_body* b = realloc(st->contact_bodies, N*sizeof(*b));
    if (b){
        st->contact_bodies = b;
    }
    size_t* o = realloc(st->contact_order, N*sizeof(*o));
    if (o){
        st->contact_order = o;
    }
    struct pfvi_compensation* c = realloc(st->contact_compensation, N*sizeof(*c));
    if (c){
        st->contact_compensation = c;
    }
    if (!b || !o || !c){
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_MEMORY, .n = N};
        return 0;
    }
    st->contact_allocated = N;
    return 1;
}

int pfvi_var_scratch(struct pfvi_state* st, size_t n){
    if (n <= st->var_allocated){
        return 1;
    }
    int ok = 1;
    st->var_real = pfvi_grow(st->var_real, n*sizeof(*st->var_real), &ok);
    st->var_sets = pfvi_grow(st->var_sets, n*sizeof(*st->var_sets), &ok);
    st->var_start = pfvi_grow(st->var_start, n*sizeof(*st->var_start), &ok);
    st->var_end = pfvi_grow(st->var_end, n*sizeof(*st->var_end), &ok);
    st->var_stage_a = pfvi_grow(st->var_stage_a, n*sizeof(*st->var_stage_a), &ok);
    st->var_predictor_a = pfvi_grow(st->var_predictor_a, n*sizeof(*st->var_predictor_a), &ok);
    st->var_stage_x = pfvi_grow(st->var_stage_x, n*sizeof(*st->var_stage_x), &ok);
    st->written_var = pfvi_grow(st->written_var, n*sizeof(*st->written_var), &ok);
    st->var_gravity_x = pfvi_grow(st->var_gravity_x, n*sizeof(*st->var_gravity_x), &ok);
    st->var_gravity_a = pfvi_grow(st->var_gravity_a, n*sizeof(*st->var_gravity_a), &ok);
    st->var_predictor_x = pfvi_grow(st->var_predictor_x, n*sizeof(*st->var_predictor_x), &ok);
    st->var_unknowns = pfvi_grow(st->var_unknowns, n*sizeof(*st->var_unknowns), &ok);
    st->var_unknowns_next = pfvi_grow(st->var_unknowns_next, n*sizeof(*st->var_unknowns_next), &ok);
    st->var_stage_start = pfvi_grow(st->var_stage_start, n*sizeof(*st->var_stage_start), &ok);
    st->var_dv = pfvi_grow(st->var_dv, n*sizeof(*st->var_dv), &ok);
    st->output_var_real = pfvi_grow(st->output_var_real, n*sizeof(*st->output_var_real), &ok);
    st->output_var_shown = pfvi_grow(st->output_var_shown, n*sizeof(*st->output_var_shown), &ok);
    st->output_var_saved_N = length_after(ok, st->output_var_saved_N, n);
    st->var_predictor_length = length_after(ok, st->var_predictor_length, n);
    if (st->output_var_N > n){
        st->output_var_N = 0;
        st->output_N = 0;
    }
    if (st->var_predictor_N > n){
        st->var_predictor_N = 0;  // (an archive's, larger than what it now describes)
    }
    if (!ok){
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_MEMORY, .n = n};
        return 0;
    }
    st->var_allocated = n;
    st->var_end_N = 0;
    return 1;
}

int pfvi_var_map(const struct reb_simulation* r, struct pfvi_state* st){
    const size_t N = r->N, n = r->N_var;
    // Each variational particle in exactly one configuration: sets edited
    // to overlap (var_config's index) would leave others unmapped, and the
    // step would read their real particle from an unset entry.
    for (size_t v=0; v<n; v++){
        st->var_real[v] = SIZE_MAX;
    }
    st->var_sets_N = 0;
    for (size_t v=0; v<r->N_var_config; v++){
        const struct reb_variational_configuration* const vc = &r->var_config[v];
        if (vc->index < 0 || (vc->order != 1 && vc->order != 2)){
            return 0;
        }
        const size_t first = (size_t)vc->index;
        const size_t size = (vc->testparticle >= 0) ? 1 : N;
        if (first > n || size > n - first || (vc->testparticle >= 0 && (size_t)vc->testparticle >= N)){
            return 0;
        }
        if (vc->order == 2){
            // (REBOUND reads the first-order sets a second-order one is made
            // from: they must lie among the variational particles)
            if (vc->index_1st_order_a < 0 || vc->index_1st_order_b < 0
                    || (size_t)vc->index_1st_order_a > n - size || (size_t)vc->index_1st_order_b > n - size){
                return 0;
            }
        }
        for (size_t i=0; i<size; i++){
            if (st->var_real[first + i] != SIZE_MAX){
                return 0;
            }
            st->var_real[first + i] = (vc->testparticle >= 0) ? (size_t)vc->testparticle : i;
        }
        if (vc->testparticle < 0){
            st->var_sets[st->var_sets_N++] = first;
        }
    }
    for (size_t v=0; v<n; v++){
        if (st->var_real[v] == SIZE_MAX){
            return 0;
        }
    }
    return 1;
}

int pfvi_particle_finite(const struct reb_particle* p){
    return isfinite(p->x) && isfinite(p->y) && isfinite(p->z)
        && isfinite(p->vx) && isfinite(p->vy) && isfinite(p->vz) && isfinite(p->m);
}

// x - x is 0 for a finite x and NaN otherwise: one sum over all particles
// says, without a branch per value, whether any is not finite.
size_t pfvi_first_not_finite(const struct reb_particle* ps, size_t N){
    double sum = 0.;
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const p = &ps[i];
        sum += ((p->x - p->x) + (p->y - p->y) + (p->z - p->z))
            + ((p->vx - p->vx) + (p->vy - p->vy) + (p->vz - p->vz)) + (p->m - p->m);
    }
    if (sum == 0.){
        return SIZE_MAX;
    }
    size_t i = 0;
    while (i < N && pfvi_particle_finite(&ps[i])){
        i++;
    }
    return i;
}

// Whether n doubles are the same bit for bit (memcmp's meaning, inlined:
// 0 and -0 differ, a NaN equals itself).
static inline int same_bits(const double* a, const double* b, int n){
    uint64_t differ = 0;
    for (int k=0; k<n; k++){
        uint64_t x, y;
        memcpy(&x, &a[k], sizeof(x));
        memcpy(&y, &b[k], sizeof(y));
        differ |= x ^ y;
    }
    return differ == 0;
}

static void force_model_keep(const struct reb_simulation* r, struct pfvi_force_model* m){
#define PFVI_KEEP(field, member) m->field = r->member;
#define PFVI_KEEP_INT(field, member) m->field = (int)r->member;
    PFVI_FORCE_MODEL_FIELDS(PFVI_KEEP, PFVI_KEEP, PFVI_KEEP_INT, PFVI_KEEP)
#undef PFVI_KEEP
#undef PFVI_KEEP_INT
}

static int force_model_unchanged(const struct reb_simulation* r, const struct pfvi_force_model* m){
    int changed = 0;
#define PFVI_SAME_DOUBLE(field, member) changed |= !same_bits(&m->field, &r->member, 1);
#define PFVI_SAME(field, member) changed |= (m->field != r->member);
#define PFVI_SAME_INT(field, member) changed |= (m->field != (int)r->member);
    PFVI_FORCE_MODEL_FIELDS(PFVI_SAME_DOUBLE, PFVI_SAME, PFVI_SAME_INT, PFVI_SAME)
#undef PFVI_SAME_DOUBLE
#undef PFVI_SAME
#undef PFVI_SAME_INT
    return !changed;
}

// Writes a kept force model's numbers back into REBOUND (not its pointers).
static void force_model_restore_numbers(struct reb_simulation* r, const struct pfvi_force_model* m){
#define PFVI_PUT(field, member) r->member = m->field;
#define PFVI_PUT_INT(field, member) r->member = (__typeof__(r->member))m->field;
#define PFVI_SKIP(field, member)
    PFVI_FORCE_MODEL_FIELDS(PFVI_PUT, PFVI_PUT, PFVI_PUT_INT, PFVI_SKIP)
#undef PFVI_PUT
#undef PFVI_PUT_INT
#undef PFVI_SKIP
}

// Whether a kept model's pointers (callbacks, extras) are REBOUND's now.
static int force_model_same_pointers(const struct reb_simulation* r, const struct pfvi_force_model* m){
    int changed = 0;
#define PFVI_SKIP(field, member)
#define PFVI_SAME(field, member) changed |= (m->field != r->member);
    PFVI_FORCE_MODEL_FIELDS(PFVI_SKIP, PFVI_SKIP, PFVI_SKIP, PFVI_SAME)
#undef PFVI_SKIP
#undef PFVI_SAME
    return !changed;
}

void pfvi_step_model_keep(const struct reb_simulation* r, struct pfvi_state* st){
    force_model_keep(r, &st->step_model);
    st->model_pending = 0;
}

void pfvi_step_model_apply_pending(struct reb_simulation* r, struct pfvi_state* st){
    if (st->model_pending){
        force_model_restore_numbers(r, &st->pending_model);
        st->model_pending = 0;
    }
}

// Whether REBOUND's numbers are a kept model's (its pointers not compared).
static int force_model_same_numbers(const struct reb_simulation* r, const struct pfvi_force_model* m){
    int changed = 0;
#define PFVI_SAME_DOUBLE(field, member) changed |= !same_bits(&m->field, &r->member, 1);
#define PFVI_SAME(field, member) changed |= (m->field != r->member);
#define PFVI_SAME_INT(field, member) changed |= (m->field != (int)r->member);
#define PFVI_SKIP(field, member)
    PFVI_FORCE_MODEL_FIELDS(PFVI_SAME_DOUBLE, PFVI_SAME, PFVI_SAME_INT, PFVI_SKIP)
#undef PFVI_SAME_DOUBLE
#undef PFVI_SAME
#undef PFVI_SAME_INT
#undef PFVI_SKIP
    return !changed;
}

int pfvi_force_model_kept(const struct reb_simulation* r, const struct pfvi_state* st){
    if (st->end_N == r->N){
        return force_model_unchanged(r, &st->cache_model);
    }
    // A loaded or copied simulation keeps no end (end_N is 0): the numbers
    // of the model its shown output was drawn under, as the snapshot saved
    // them (its callbacks' addresses are new). Without them, G changed on a
    // copy went on from the run's state drawn under the old G (a hostile
    // trial: 9e-5 off). An archive written before they were saved has none:
    // taken as kept, as then.
    return !st->output_model_saved || force_model_same_numbers(r, &st->output_model);
}

void pfvi_output_keep_model(const struct reb_simulation* r, struct pfvi_state* st){
    force_model_keep(r, &st->output_model);
    st->output_model_saved = 1;
}

int pfvi_end_is_start(const struct reb_simulation* r, const struct pfvi_state* st){
    return st->cache_N == r->N && pfvi_state_is_end(r, st);
}

int pfvi_state_is_end(const struct reb_simulation* r, const struct pfvi_state* st){
    const size_t N = r->N;
    if (st->end_N != N || st->cache_t != r->t || !force_model_unchanged(r, &st->cache_model)){
        return 0;
    }
    const struct reb_particle* const ps = r->particles;
    const struct pfvi_end_state* const e = st->end;
    int same = 1;
    for (size_t i=0; i<N; i++){
        same &= same_bits(&ps[i].x, e[i].xv, 6) & same_bits(&ps[i].m, &e[i].m, 1);
    }
    return same;
}

void pfvi_keep_end(const struct reb_simulation* r, struct pfvi_state* st, size_t N){
    const struct reb_particle* const ps = r->particles;
    struct pfvi_end_state* const e = st->end;
    for (size_t i=0; i<N; i++){
        memcpy(e[i].xv, &ps[i].x, sizeof(e[i].xv));
        e[i].m = ps[i].m;
        e[i].a[0] = ps[i].ax; e[i].a[1] = ps[i].ay; e[i].a[2] = ps[i].az;
    }
    st->cache_N = N;
    st->cache_t = r->t;
    force_model_keep(r, &st->cache_model);
    st->end_N = N;
    st->end_saved_N = N;
}

void pfvi_keep_end_model(const struct reb_simulation* r, struct pfvi_state* st, size_t N){
    st->cache_N = N;
    st->cache_t = r->t;
    force_model_keep(r, &st->cache_model);
    st->end_N = N;
    st->end_saved_N = N;
}

// A particle the user edited (or replaced) since the last step keeps nothing
// from its predecessor: its compensation is cleared and the stage predictor
// dropped, so that continuing equals starting afresh from the edited state.
void pfvi_forget_edited(const struct reb_simulation* r, struct pfvi_state* st){
    const size_t N = r->N;
    if ((st->end_N != N && st->end_saved_N != N) || st->N_compensation != N){
        return;  // N changed (compensation already cleared) or no step to compare with
    }
    const struct reb_particle* const ps = r->particles;
    const struct pfvi_end_state* const e = st->end;
    int edited = 0;
    for (size_t i=0; i<N; i++){
        if (!(same_bits(&ps[i].x, e[i].xv, 6) && same_bits(&ps[i].m, &e[i].m, 1))){
            st->compensation[i] = (struct pfvi_compensation){{0., 0., 0.}, {0., 0., 0.}};
            edited = 1;
        }
    }
    if (edited){
        st->predictor_stages = 0;
        st->rho = 0.;  // the symmetric step's density no longer describes them
        st->track_edited = 1;
        st->density_scale = 1.;
        st->density_N = 0;
        pfvi_replay_clear(st);  // nor does the way so far
        st->replay_next = 0;
    }
}

size_t pfvi_ghost_box_count(const struct reb_simulation* r){
    const size_t nx = 2*(size_t)(r->N_ghost_x > 0 ? r->N_ghost_x : 0) + 1;
    const size_t ny = 2*(size_t)(r->N_ghost_y > 0 ? r->N_ghost_y : 0) + 1;
    const size_t nz = 2*(size_t)(r->N_ghost_z > 0 ? r->N_ghost_z : 0) + 1;
    return nx*ny*nz;
}

void pfvi_ghost_boxes(const struct reb_simulation* r, struct reb_vec6d* images){
    if (pfvi_ghost_box_count(r) == 1){
        images[0] = (struct reb_vec6d){0., 0., 0., 0., 0., 0.};
        return;
    }
    // REBOUND's own boxes, in lexicographic order from (-N_x, -N_y, -N_z):
    // image n - 1 - g is the mirror of image g.
    size_t g = 0;
    for (int i=-r->N_ghost_x; i<=r->N_ghost_x; i++){
        for (int j=-r->N_ghost_y; j<=r->N_ghost_y; j++){
            for (int k=-r->N_ghost_z; k<=r->N_ghost_z; k++){
                // (REBOUND's routine reads r; its signature does not say so)
                images[g++] = reb_boundary_get_ghostbox((struct reb_simulation*)r, i, j, k);
            }
        }
    }
}

int pfvi_field_of(const struct reb_simulation* r, struct pfvi_state* st, struct pfvi_field* f){
    const size_t n = pfvi_ghost_box_count(r);
    if (n > st->images_allocated){
        struct reb_vec6d* const grown = realloc(st->images, n*sizeof(*grown));
        if (!grown){
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_MEMORY, .n = n};
            return 0;
        }
        st->images = grown;
        st->images_allocated = n;
    }
    pfvi_ghost_boxes(r, st->images);
    if (r->N > st->field_blocks_N){
        // (grown with N only; without it the scans gather as they go)
        const size_t n_blocks = (r->N + 3)/4;
        struct pfvi_lanes_block* const blocks = realloc(st->field_blocks, n_blocks*sizeof(*blocks));
        if (blocks){
            st->field_blocks = blocks;
            st->field_blocks_N = 4*n_blocks;
        }
    }
    *f = (struct pfvi_field){
        .G = (r->gravity == REB_GRAVITY_NONE) ? 0. : r->G,
        .softening2 = r->softening*r->softening,
        .N_active = r->N_active,
        .n_images = n,
        .images = st->images,
        .blocks = st->field_blocks,
        .blocks_N = st->field_blocks_N,
    };
    return 1;
}

int pfvi_t_lo_plausible(double t_lo, double t){
    return fabs(t_lo) <= PFVI_T_LO_MAX*fmax(1., fabs(t));
}

double pfvi_t_lo(const struct reb_simulation* r, const struct pfvi_state* st){
    return (r->t == st->t_compensated && pfvi_t_lo_plausible(st->t_compensation, r->t)) ? st->t_compensation : 0.;
}

void pfvi_discard_implausible(const struct reb_simulation* r, struct pfvi_state* st){
    // The predictor: a step of its own, at a finite time, with finite stages.
    int predictor = st->predictor_stages != 0;
    predictor &= isfinite(st->predictor_h) && st->predictor_h != 0. && isfinite(st->predictor_t);
    predictor &= st->predictor_stages >= PFVI_STAGES_MIN && st->predictor_stages <= PFVI_STAGES_MAX;
    const size_t n = (st->predictor_N <= st->N_allocated) ? st->predictor_N : 0;
    for (size_t i=0; predictor && i<n; i++){
        for (int k=0; k<st->predictor_stages; k++){
            for (int c=0; c<3; c++){
                predictor &= isfinite(st->predictor_a[i][k][c]) && isfinite(st->predictor_x[i][k][c]);
            }
        }
    }
    if (!predictor){
        st->predictor_stages = 0;
    }
    // The variational particles' stages: finite (deviations may be large, never infinite).
    const size_t nv = (st->var_predictor_N <= st->var_allocated) ? st->var_predictor_N : 0;
    int var_predictor = predictor && nv > 0;
    for (size_t v=0; var_predictor && v<nv; v++){
        for (int k=0; k<st->predictor_stages; k++){
            for (int c=0; c<3; c++){
                var_predictor &= isfinite(st->var_predictor_a[v][k][c]) && isfinite(st->var_predictor_x[v][k][c]);
            }
        }
    }
    if (!var_predictor){
        st->var_predictor_N = 0;
    }
    // The symmetric track, its scale and the time's carried rounding.
    if (!(st->rho > 0. && isfinite(st->rho)) || !(st->rho_sign == 1. || st->rho_sign == -1.)
            || !(st->track_done >= 0. && isfinite(st->track_done)) || !(st->track_kappa > 0. && isfinite(st->track_kappa))){
        st->rho = 0.;
    }
    if (!(st->density_scale >= 1. && st->density_scale <= PFVI_DENSITY_SCALE_MAX)){
        st->density_scale = 1.;
    }
    if (!(fabs(st->track_mismatch) <= PFVI_TRACK_MISMATCH_MAX)){
        st->track_mismatch = 0.;
    }
    // The steady track's hold and records (the track restarts without them).
    const struct pfvi_steady* const sd = &st->steady;
    const int steady_sane = (sd->hold == 0 || sd->hold == 1) && sd->n >= 0 && sd->n <= PFVI_STEADY_WINDOW
        && isfinite(sd->lo + sd->hi + sd->t0 + sd->span + sd->entry_t + sd->entry_rho + sd->exit_t + sd->exit_held
            + sd->exit_after)
        && (sd->entry_sign == 0. || sd->entry_sign == 1. || sd->entry_sign == -1.)
        && (sd->exit_sign == 0. || sd->exit_sign == 1. || sd->exit_sign == -1.);
    if (!steady_sane){
        memset(&st->steady, 0, sizeof(st->steady));
        st->rho = 0.;
    }
    if (!(st->track_seen_lo <= st->track_seen_hi)){
        st->track_seen_lo = st->track_seen_hi = r->t;  // NaN or crossed: everything ahead is unseen
    }
    if (!pfvi_t_lo_plausible(st->t_compensation, r->t)){
        st->t_compensation = 0.;
    }
    // The carried low-order parts of x and v: below the precision of the
    // vectors they belong to. Each component is judged against the vector's
    // largest, not its own: a velocity component that ends a step near zero
    // (a turning point) keeps the rounding of an increment as large as the
    // other components, which the velocity increment's compensated sum
    // carries (judged by its own component, it was dropped at every call's
    // start, and steps(25) + steps(75) of a circle at 100 fixed steps an orbit
    // no longer gave the bits of steps(100): a hostile trial).
    const struct reb_particle* const ps = r->particles;
    const size_t m = (st->N_compensation <= r->N) ? st->N_compensation : 0;
    for (size_t i=0; i<m; i++){
        const double x = fmax(fmax(fabs(ps[i].x), fabs(ps[i].y)), fmax(fabs(ps[i].z), DBL_MIN));
        const double v = fmax(fmax(fabs(ps[i].vx), fabs(ps[i].vy)), fmax(fabs(ps[i].vz), DBL_MIN));
        const struct pfvi_compensation* const comp = &st->compensation[i];
        int plausible = 1;
        for (int c=0; c<3; c++){
            plausible &= fabs(comp->x[c]) <= 1e-10*x + DBL_MIN;
            plausible &= fabs(comp->v[c]) <= 1e-10*v + DBL_MIN;
        }
        if (!plausible){
            st->compensation[i] = (struct pfvi_compensation){{0., 0., 0.}, {0., 0., 0.}};
        }
    }
}

int pfvi_var_is_end(const struct reb_simulation* r, const struct pfvi_state* st){
    const size_t n = r->N_var;
    if (st->var_end_N != n || n == 0){
        return 0;
    }
    const struct reb_particle* const pv = r->particles_var;
    int same = 1;
    for (size_t v=0; v<n; v++){
        same &= same_bits(&pv[v].x, st->var_end[v].xv, 6) & same_bits(&pv[v].m, &st->var_end[v].m, 1);
    }
    return same;
}

void pfvi_var_keep_end(const struct reb_simulation* r, struct pfvi_state* st){
    const size_t n = r->N_var;
    const struct reb_particle* const pv = r->particles_var;
    for (size_t v=0; v<n; v++){
        memcpy(st->var_end[v].xv, &pv[v].x, sizeof(st->var_end[v].xv));
        st->var_end[v].m = pv[v].m;
        st->var_end[v].a[0] = pv[v].ax; st->var_end[v].a[1] = pv[v].ay; st->var_end[v].a[2] = pv[v].az;
    }
    st->var_end_N = n;
}

void pfvi_roll_back(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    memcpy(r->particles, st->start, N*sizeof(struct reb_particle));
    if (st->var_N && st->var_N == r->N_var){
        memcpy(r->particles_var, st->var_start, st->var_N*sizeof(struct reb_particle));
    }
    r->t = t0;
    st->cache_N = 0;
}

// Room for n entries of origin. Only a callback that adds or removes
// particles during a step gets here, never the hot path.
static int pfvi_origin_reserve(struct pfvi_state* st, size_t n){
    if (n <= st->origin_allocated){
        return 1;
    }
    size_t* const grown = realloc(st->origin, n*sizeof(*grown));
    if (!grown){
        st->in_step = PFVI_STEP_UNTRACKED;
        return 0;
    }
    st->origin = grown;
    st->origin_allocated = n;
    return 1;
}

// Whether a change of N is to be tracked now (a step is running): at the
// first change, origin becomes the identity over the step's particles.
static int pfvi_origin_tracking(struct pfvi_state* st){
    if (st->in_step == PFVI_STEP_IDLE || st->in_step == PFVI_STEP_UNTRACKED){
        return 0;
    }
    if (st->in_step == PFVI_STEP_RUNNING){
        if (!pfvi_origin_reserve(st, st->step_N + 1)){
            return 0;
        }
        for (size_t i=0; i<st->step_N; i++){
            st->origin[i] = i;
        }
        st->origin_N = st->step_N;
        st->in_step = PFVI_STEP_TRACKING;
    }
    return 1;
}

void pfvi_track_added(struct pfvi_state* st){
    if (pfvi_origin_tracking(st) && pfvi_origin_reserve(st, st->origin_N + 1)){
        st->origin[st->origin_N++] = SIZE_MAX;  // REBOUND appends
    }
}

void pfvi_track_removed(struct pfvi_state* st, size_t index){
    if (pfvi_origin_tracking(st) && index < st->origin_N){  // REBOUND refuses an index out of range
        memmove(&st->origin[index], &st->origin[index + 1], (st->origin_N - index - 1)*sizeof(*st->origin));
        st->origin_N--;
    }
}

// A callback added or removed particles during a force evaluation: t and
// every particle still there go back to the step's start; the removed ones
// are gone and the added ones stay as added (the callback's doing).
static void pfvi_roll_back_changed_N(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    const size_t now = r->N;
    st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_N_CHANGED, .n = N, .n_after = now, .t = r->t};
    r->t = t0;
    st->cache_N = 0;
    if (st->in_step != PFVI_STEP_TRACKING || st->origin_N != now){
        return;  // flag 0: the particles could not be restored (out of memory)
    }
    for (size_t k=0; k<now; k++){
        if (st->origin[k] == SIZE_MAX){
            st->fault.added++;
        }else{
            r->particles[k] = st->start[st->origin[k]];
            st->fault.kept++;
        }
    }
    st->fault.flag = 1;
}

// The particles' fields and t as pfvi set them for a force evaluation.
static void written_keep(const struct reb_simulation* r, struct pfvi_state* st, size_t N){
    const struct reb_particle* const ps = r->particles;
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const p = &ps[i];
        st->written[i] = (struct pfvi_written){{p->x, p->y, p->z, p->vx, p->vy, p->vz, p->m}};
    }
    // The variational particles too: their masses enter REBOUND's
    // variational gravity, which the own pass computes for every stage
    // before the first call (an edit there would act at the next stage
    // through REBOUND's routine and not through the pass).
    for (size_t v=0; v<st->var_N && r->particles_var; v++){
        const struct reb_particle* const p = &r->particles_var[v];
        st->written_var[v] = (struct pfvi_written){{p->x, p->y, p->z, p->vx, p->vy, p->vz, p->m}};
    }
}

// The first field a callback changed during the evaluation: 1 (fault
// recorded) or 0. Compared bit for bit (a NaN written is a change, too).
static int written_changed(const struct reb_simulation* r, struct pfvi_state* st, size_t N, double t){
    if (memcmp(&r->t, &t, sizeof(t)) != 0){
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_PARTICLE_EDITED, .particle = SIZE_MAX, .t = t};
        return 1;
    }
    const struct reb_particle* const ps = r->particles;
    for (size_t i=0; i<N; i++){
        const struct reb_particle* const p = &ps[i];
        const double now[7] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->m};
        if (memcmp(now, st->written[i].value, sizeof(now)) != 0){
            int k = 0;
            while (k < 6 && memcmp(&now[k], &st->written[i].value[k], sizeof(double)) == 0){
                k++;
            }
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_PARTICLE_EDITED, .particle = i, .t = t, .flag = k};
            return 1;
        }
    }
    for (size_t v=0; v<st->var_N && r->particles_var; v++){
        const struct reb_particle* const p = &r->particles_var[v];
        const double now[7] = {p->x, p->y, p->z, p->vx, p->vy, p->vz, p->m};
        if (memcmp(now, st->written_var[v].value, sizeof(now)) != 0){
            int k = 0;
            while (k < 6 && memcmp(&now[k], &st->written_var[v].value[k], sizeof(double)) == 0){
                k++;
            }
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_PARTICLE_EDITED, .particle = v, .t = t, .flag = k,
                .n = 1};
            return 1;
        }
    }
    return 0;
}

// The number of messages REBOUND keeps (librebound exports it; rebound.h
// does not declare it).
extern const int reb_messages_max_N;

// REBOUND's error messages waiting to be read (Python keeps them,
// save_messages: each is raised when the call returns), and the newest
// message: REBOUND keeps at most reb_messages_max_N, dropping the oldest for
// a new one, so that with the queue full a new error can leave the count as
// it was (10 errors queued, then a refusal: missed; a hostile trial). Its
// string is then a new allocation, while the newest before it is still held.
struct pfvi_error_mark pfvi_rebound_errors(const struct reb_simulation* r){
    struct pfvi_error_mark m = {0, NULL};
    for (int i=0; r->messages != NULL && i<reb_messages_max_N; i++){
        m.n += (r->messages[i] != NULL && r->messages[i][0] == 'e');
        m.newest = (r->messages[i] != NULL) ? r->messages[i] : m.newest;
    }
    return m;
}

int pfvi_rebound_error_since(const struct reb_simulation* r, struct pfvi_error_mark before){
    const struct pfvi_error_mark now = pfvi_rebound_errors(r);
    return now.n > before.n || (now.newest != before.newest && now.newest != NULL && now.newest[0] == 'e');
}

static void message(struct reb_simulation* r, int error, const char* fmt, va_list args){
    char msg[4*REB_STRING_SIZE_MAX];
    const int n = vsnprintf(msg, sizeof(msg), fmt, args);
    const size_t kept = REB_STRING_SIZE_MAX - 2;
    if (n > 0 && (size_t)n > kept){
        size_t end = 0;
        for (size_t i=0; i + 1 < kept; i++){
            end = ((msg[i] == '.' || msg[i] == ';' || msg[i] == ':') && msg[i+1] == ' ') ? i : end;
        }
        msg[end] = '.';
        msg[end + 1] = '\0';
    }
    if (error){
        reb_simulation_error(r, msg);
    }else{
        reb_simulation_warning(r, msg);
    }
}

void pfvi_error(struct reb_simulation* r, const char* fmt, ...){
    va_list args;
    va_start(args, fmt);
    message(r, 1, fmt, args);
    va_end(args);
}

void pfvi_warning(struct reb_simulation* r, const char* fmt, ...){
    va_list args;
    va_start(args, fmt);
    message(r, 0, fmt, args);
    va_end(args);
}

int pfvi_forces_run_user_code(const struct reb_simulation* r){
    return r->additional_forces != NULL || r->gravity == REB_GRAVITY_CUSTOM;
}

// REBOUND's update of the accelerations, or with gravity_given (the basic
// gravity already in the particles' accelerations, as REBOUND's routine would
// leave it: pfvi_gravity_stages) the rest of that update, the additional
// forces; then the checks of what the forces did.
static int update_forces(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0, int gravity_given){
    // Only user code (a force callback, custom gravity) can edit particles
    // during an evaluation; REBOUND's own gravity does not.
    const int guarded = pfvi_forces_run_user_code(r);
    const double t = r->t;
    if (guarded){
        written_keep(r, st, N);
    }
    const struct pfvi_error_mark errors = pfvi_rebound_errors(r);
    if (gravity_given){
        r->additional_forces(r);
    }else{
        reb_simulation_update_acceleration(r);
    }
    st->statistics.n_force_evaluations++;
    if (st->reentry_refused){
        r->status = (enum REB_STATUS)st->status_at_start;
        r->dt = st->dt_at_start;
        st->reentry_refused = 0;
    }
    if (r->N != N){
        pfvi_roll_back_changed_N(r, st, N, t0);
        return 0;
    }
    if (r->N_var != st->var_N && (st->var_N || guarded)){
        // (REBOUND moved the variational particles' array: the step's
        // pointers into it are stale, and their start does not fit it.)
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_VARIATIONS_CHANGED, .n = st->var_N, .particle = r->N_var,
            .t = t};
        pfvi_roll_back(r, st, N, t0);
        return 0;
    }
    if (pfvi_rebound_error_since(r, errors)){
        // An error inside the forces (a REBOUNDx effect without its
        // parameter, a callback calling reb_simulation_error): the forces
        // are not to be used. The step is refused, its state restored; the
        // error is REBOUND's message, raised when the call returns.
        st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_REBOUND_ERROR, .t = t};
        pfvi_roll_back(r, st, N, t0);
        return 0;
    }
    if (guarded && written_changed(r, st, N, t)){
        // A callback edited a particle or t inside the step: what it meant
        // ("between" which stage points?) has no between-steps equivalent.
        pfvi_roll_back(r, st, N, t0);
        return 0;
    }
    if (!force_model_unchanged(r, &st->step_model)){
        // A callback changed the force model during the step. Its numbers
        // (G, softening, N_active, the gravity mode, ...) act from the next
        // step: kept aside, and the step's restored. A replaced callback
        // cannot be restored (the old one may be gone): the step is refused.
        if (!force_model_same_pointers(r, &st->step_model)){
            st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_CALLBACK_CHANGED, .t = r->t};
            pfvi_roll_back(r, st, N, t0);
            return 0;
        }
        force_model_keep(r, &st->pending_model);
        st->model_pending = 1;
        force_model_restore_numbers(r, &st->step_model);
    }
    const struct reb_particle* const ps = r->particles;
    double sum = 0.;  // as in pfvi_first_not_finite
    for (size_t i=0; i<N; i++){
        sum += (ps[i].ax - ps[i].ax) + (ps[i].ay - ps[i].ay) + (ps[i].az - ps[i].az);
    }
    for (size_t i=0; sum != 0. && i<N; i++){
        if (!(isfinite(ps[i].ax) && isfinite(ps[i].ay) && isfinite(ps[i].az))){
            // A position or velocity that overflowed in the step is the cause
            // to name, not the force it produced.
            size_t j = 0;
            while (j < N && pfvi_particle_finite(&ps[j])){
                j++;
            }
            if (j < N){
                const int position = !(isfinite(ps[j].x) && isfinite(ps[j].y) && isfinite(ps[j].z));
                st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_OVERFLOW, .particle = j, .t0 = t0, .flag = position};
            }else{
                st->fault = (struct pfvi_fault){.kind = PFVI_FAULT_FORCE, .particle = i, .t = r->t};
            }
            pfvi_roll_back(r, st, N, t0);
            return 0;
        }
    }
    return 1;
}

int pfvi_update_acceleration(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    return update_forces(r, st, N, t0, 0);
}

int pfvi_update_additional_forces(struct reb_simulation* r, struct pfvi_state* st, size_t N, double t0){
    return update_forces(r, st, N, t0, 1);
}

// The stopping rule of IRKGL16 (Antonana, Makazaga & Murua 2017): iterate
// while the largest relative change decreases; once it is zero or stops
// decreasing it is round-off, and the iteration has converged if that is at
// most PFVI_ITERATION_TOLERANCE. A change that is not finite has failed.
// No shortcut below round-off: an iterate accepted one round early carries
// the first iterate's (the predictor's) error, below the doubles' spacing but
// the same in every step, and the energy drifts with it (docs/roundoff.md).
enum pfvi_iteration pfvi_iteration_verdict(double change, double previous, int last_round){
    if (!isfinite(change)){
        return PFVI_FAILED;
    }
    if (change == 0. || change >= previous || last_round){
        return (change <= PFVI_ITERATION_TOLERANCE) ? PFVI_CONVERGED : PFVI_FAILED;
    }
    return PFVI_ITERATE;
}

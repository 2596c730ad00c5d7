/**
 * pfvi_gravity.c: REBOUND's basic gravity at every stage of a round in one
 * pass over the pairs.
 *
 * A round needs the forces at s - 1 stage points. Through REBOUND that is
 * s - 1 trips: the stage positions written into r->particles, REBOUND's
 * reb_simulation_update_acceleration, the accelerations read back, and for
 * each trip the ghost box looked up and every particle's acceleration
 * zeroed (docs/performance.md: at N = 2 and 3 the trips cost more than the
 * gravity). Here the pairs are the outer loops and the stages the inner one,
 * over pfvi's own stage arrays.
 *
 * The arithmetic is REBOUND's reb_gravity_basic_calculate_acceleration
 * (src/gravity.c, the same in 5.0 to 5.2, built without OpenMP) operation
 * for operation: the ghost boxes in its order, the image shift added to
 * particle i's coordinate, the softened distance, G/r^3, the same pairs (i from 1, j < i, among the
 * N_active; then each test particle against the active ones, pulling them
 * with testparticle_type 1) in the same order. Each stage's sums therefore
 * add the same terms in the same order as REBOUND's: the accelerations are
 * bit for bit REBOUND's, and so is every trajectory (tests/test_gravity.py
 * compares them with the REBOUND path forced).
 *
 * Used where REBOUND's routine would compute its basic gravity (no ignored
 * terms, ghost boxes only where their shifts do not depend on time: a
 * periodic box, not a shearing sheet): alone (pfvi_gravity_own), or beside
 * additional forces (pfvi_gravity_own_beside_forces: a callback, REBOUNDx's,
 * velocity-dependent or not), which are then called at each stage with the
 * particles there and this gravity in their accelerations, as REBOUND's
 * routine would call them; or with variational particles of first order,
 * each set a variation of every particle (MEGNO's, add_variation()'s), whose
 * forces are REBOUND's reb_gravity_basic_calculate_acceleration_var computed
 * the same way (pfvi_gravity_own_variational, without ghost boxes; with
 * additional forces called beside it, pfvi_gravity_own_variational_beside_forces).
 * Everything else (a test particle's variation, second order) goes through
 * REBOUND as before.
 */
#include <math.h>
#include <string.h>
#include "pfvi.h"
#include "boundary.h"

// REBOUND's update of the accelerations would compute its basic gravity (and
// nothing else for the particles, whatever else it calls after it).
// (The real particles' gravity; the variational particles' is asked apart.)
static int basic_real_gravity(const struct reb_simulation* r, size_t N){
    // (Ghost boxes whose shifts do not depend on t: a shearing sheet's move
    // with it, and the stages of a pass are at different times.)
    const int ghosts = r->N_ghost_x != 0 || r->N_ghost_y != 0 || r->N_ghost_z != 0;
    return r->gravity == REB_GRAVITY_BASIC
        && r->gravity_ignore_terms == 0 && (!ghosts || r->boundary != REB_BOUNDARY_SHEAR)
        && (r->N_active == SIZE_MAX || r->N_active <= N);
}

static int basic_gravity(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    return basic_real_gravity(r, N) && r->N_var == 0 && st->var_N == 0;
}

int pfvi_gravity_own(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    return basic_gravity(r, st, N) && r->additional_forces == NULL;
}

int pfvi_gravity_two_alone(const struct reb_simulation* r, size_t N){
    // (G > 0: the predictor draws the pair's pull along a Kepler orbit only
    // then; a repulsive G leaves the whole force to the rest.)
    return N == 2 && r->G > 0. && basic_real_gravity(r, N) && r->additional_forces == NULL
        && r->N_ghost_x == 0 && r->N_ghost_y == 0 && r->N_ghost_z == 0
        && (r->N_active == SIZE_MAX || r->N_active >= N);
}

int pfvi_gravity_own_beside_forces(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    return basic_gravity(r, st, N) && r->additional_forces != NULL;
}

// Variational particles whose forces REBOUND's routine would compute with
// its basic variational gravity: every configuration of first order and a
// whole set of N (a variation of every particle, as MEGNO's and
// add_variation()'s are; pfvi_var_map listed them in var_sets) and no ghost
// boxes (REBOUND's variational gravity has none); alone, or with additional
// forces called after it.
static int basic_variational_gravity(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    if (!(basic_real_gravity(r, N) && st->var_N > 0 && r->N_var == st->var_N
            && r->N_ghost_x == 0 && r->N_ghost_y == 0 && r->N_ghost_z == 0 && st->var_sets_N == r->N_var_config)){
        return 0;
    }
    for (size_t c=0; c<r->N_var_config; c++){
        const struct reb_variational_configuration* const vc = &r->var_config[c];
        if (vc->order != 1 || vc->testparticle >= 0 || vc->index < 0 || (size_t)vc->index != st->var_sets[c]){
            return 0;
        }
    }
    return 1;
}

int pfvi_gravity_own_variational(const struct reb_simulation* r, const struct pfvi_state* st, size_t N){
    return r->additional_forces == NULL && basic_variational_gravity(r, st, N);
}

int pfvi_gravity_own_variational_beside_forces(const struct reb_simulation* r, const struct pfvi_state* st,
        size_t N){
    return r->additional_forces != NULL && basic_variational_gravity(r, st, N);
}

#define LANES PFVI_STAGES_MAX

// The shift of REBOUND's ghost box (i, j, k), as reb_boundary_get_ghostbox
// computes it (boundary.c, the same in 5.0 to 5.2): its operations, so its
// bits, the sign of a zero included (an unset root_size is -1: the box
// (0, 0, 0) of an open boundary is then shifted by -0), without the call
// and the struct it returns (once per box and pass: 1.4% of the step at
// N = 3, 2% at N = 2). A shearing sheet's boxes move with t: REBOUND's own.
static inline void ghost_shift(const struct reb_simulation* r, int i, int j, int k, double g[3]){
    switch (r->boundary){
        case REB_BOUNDARY_OPEN:
        case REB_BOUNDARY_PERIODIC:
            g[0] = (r->root_size*(double)r->N_root_x)*(double)i;
            g[1] = (r->root_size*(double)r->N_root_y)*(double)j;
            g[2] = (r->root_size*(double)r->N_root_z)*(double)k;
            return;
        case REB_BOUNDARY_SHEAR:
            {
                const struct reb_vec6d box = reb_boundary_get_ghostbox((struct reb_simulation*)r, i, j, k);
                g[0] = box.x; g[1] = box.y; g[2] = box.z;
                return;
            }
        default:
            g[0] = 0.; g[1] = 0.; g[2] = 0.;
            return;
    }
}

// The pair (i, j)'s terms in lanes l0 .. l1 - 1 (constants at each call), as REBOUND's loop body; with
// pull_j = 0 (a test particle i of type 0) j feels nothing. The lanes are
// independent, so the compiler vectorises them (SSE2's packed square root
// and division round as the scalar ones do: the same bits).
static inline __attribute__((always_inline)) void pair_terms(const double (*restrict xi)[LANES],
        const double (*restrict xj)[LANES], double (*restrict ai)[LANES], double (*restrict aj)[LANES],
        double mi, double mj, double G, double softening2, const double g[3], int pull_j,
        const int l0, const int l1){
    for (int l=l0; l<l1; l++){
        const double dx = (g[0] + xi[0][l]) - xj[0][l];
        const double dy = (g[1] + xi[1][l]) - xj[1][l];
        const double dz = (g[2] + xi[2][l]) - xj[2][l];
        const double _r = sqrt(dx*dx + dy*dy + dz*dz + softening2);
        const double prefact = G/(_r*_r*_r);
        const double prefactj = -prefact*mj;
        ai[0][l] += prefactj*dx;
        ai[1][l] += prefactj*dy;
        ai[2][l] += prefactj*dz;
        if (pull_j){
            const double prefacti = prefact*mi;
            aj[0][l] += prefacti*dx;
            aj[1][l] += prefacti*dy;
            aj[2][l] += prefacti*dz;
        }
    }
}

// Every pair's terms in lanes l0 .. l1 - 1 (constants at each call: each
// its own vectorised loop).
static inline __attribute__((always_inline)) void all_pairs(const struct reb_particle* ps, size_t N,
        size_t N_active, int pull, const double (*restrict X)[3][LANES], double (*restrict A)[3][LANES],
        double G, double softening2, const double g[3], const int l0, const int l1){
    for (size_t i=1; i<N_active; i++){
        for (size_t j=0; j<i; j++){
            pair_terms(X[i], X[j], A[i], A[j], ps[i].m, ps[j].m, G, softening2, g, 1, l0, l1);
        }
    }
    const size_t first_test = (N_active > 1) ? N_active : 1;
    for (size_t i=first_test; i<N; i++){
        for (size_t j=0; j<N_active; j++){
            if (pull){
                pair_terms(X[i], X[j], A[i], A[j], ps[i].m, ps[j].m, G, softening2, g, 1, l0, l1);
            }else{
                pair_terms(X[i], X[j], A[i], A[j], ps[i].m, ps[j].m, G, softening2, g, 0, l0, l1);
            }
        }
    }
}

// Positions x[i][k] of n bodies into lanes X[i][c][l], lane l holding stage
// l and lanes outside k0 .. k1 the nearest stage (finite values, computed
// and dropped; each lane's stage chosen once, not per component and body),
// and the sums A zeroed (stores of vectors, not memset: its rep stosb
// counts a byte an instruction under callgrind).
static inline __attribute__((always_inline)) void stages_into_lanes(size_t n, const double (*x)[PFVI_STAGES_MAX][3],
        double (*restrict X)[3][LANES], double (*restrict A)[3][LANES], int k0, int k1){
    int stage_of[LANES];
    for (int l=0; l<LANES; l++){
        stage_of[l] = (l < k0) ? k0 : (l > k1) ? k1 : l;
    }
    const pfvi_lanes zero = {0., 0., 0., 0.};
    for (size_t i=0; i<n; i++){
        for (int l=0; l<LANES; l++){
            const int k = stage_of[l];
            X[i][0][l] = x[i][k][0];
            X[i][1][l] = x[i][k][1];
            X[i][2][l] = x[i][k][2];
        }
        for (int c=0; A && c<3; c++){
            memcpy(&A[i][c][0], &zero, sizeof(zero));
            memcpy(&A[i][c][4], &zero, sizeof(zero));
        }
    }
}

// Compiled twice, for AVX2 (4 lanes a vector) and for any x86-64 (SSE2, 2),
// chosen by the processor at load time; elsewhere once. No FMA either way.
PFVI_VECTOR_CLONES
int pfvi_gravity_stages(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        const double (*x)[PFVI_STAGES_MAX][3], double (*a)[PFVI_STAGES_MAX][3], int k0, int k1){
    const struct reb_particle* const ps = r->particles;
    const double G = r->G;
    const double softening2 = r->softening*r->softening;
    const size_t N_active = (r->N_active == SIZE_MAX) ? N : r->N_active;
    double (*restrict X)[3][LANES] = st->gravity_x;
    double (*restrict A)[3][LANES] = st->gravity_a;
    stages_into_lanes(N, x, X, A, k0, k1);
    // Stages within one block of 4 lanes (the end stage's pass alone; s <= 5)
    // take that block alone.
    const int pull = r->testparticle_type;
    const double (*const Xc)[3][LANES] = (const double (*)[3][LANES])X;
    // REBOUND's ghost boxes in REBOUND's order, each box's pairs in full
    // before the next (the one box (0, 0, 0) when there are none: a shift
    // of zero, added all the same, its sign of zero included).
    for (int gbx=-r->N_ghost_x; gbx<=r->N_ghost_x; gbx++){
        for (int gby=-r->N_ghost_y; gby<=r->N_ghost_y; gby++){
            for (int gbz=-r->N_ghost_z; gbz<=r->N_ghost_z; gbz++){
                double g[3];
                ghost_shift(r, gbx, gby, gbz, g);
                if (k1 < 4){
                    all_pairs(ps, N, N_active, pull, Xc, A, G, softening2, g, 0, 4);
                }else if (k0 >= 4){
                    all_pairs(ps, N, N_active, pull, Xc, A, G, softening2, g, 4, LANES);
                }else{
                    all_pairs(ps, N, N_active, pull, Xc, A, G, softening2, g, 0, LANES);
                }
            }
        }
    }
    // Whether every force is finite, as the caller's check of REBOUND's
    // accelerations asks: a - a is 0 for a finite a and NaN otherwise, and a
    // sum of them NaN if any is, in whatever order it is added. The lanes
    // outside k0 .. k1 repeat a stage inside (the same inputs, the same
    // forces), so all lanes give the verdict of k0 .. k1's.
    pfvi_lanes nan = {0., 0., 0., 0.};
    for (size_t i=0; i<N; i++){
        for (int c=0; c<3; c++){
            pfvi_lanes lo, hi;
            memcpy(&lo, &A[i][c][0], sizeof(lo));
            memcpy(&hi, &A[i][c][4], sizeof(hi));
            nan += (lo - lo) + (hi - hi);
        }
    }
    for (size_t i=0; i<N; i++){
        for (int k=k0; k<=k1; k++){
            a[i][k][0] = A[i][0][k]; a[i][k][1] = A[i][1][k]; a[i][k][2] = A[i][2][k];
        }
    }
    double lanes[4];
    memcpy(lanes, &nan, sizeof(lanes));
    return (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) == 0.;
}

// The pair (i, j)'s variational terms in lanes l0 .. l1 - 1, as the loop
// body of REBOUND's reb_gravity_basic_calculate_acceleration_var (first
// order; the same in 5.0 to 5.2): the tidal tensor of the unsoftened
// distance applied to the pair's variation, and the variations of the
// masses; with pull_j = 0 (a test particle i of type 0) j feels nothing.
static inline __attribute__((always_inline)) void var_pair_terms(const double (*restrict xi)[LANES],
        const double (*restrict xj)[LANES], const double (*restrict di)[LANES], const double (*restrict dj)[LANES],
        double (*restrict dai)[LANES], double (*restrict daj)[LANES], double Gmi, double Gmj, double dGmi, double dGmj,
        int pull_j, const int l0, const int l1){
    for (int l=l0; l<l1; l++){
        const double dx = xi[0][l] - xj[0][l];
        const double dy = xi[1][l] - xj[1][l];
        const double dz = xi[2][l] - xj[2][l];
        const double r2 = dx*dx + dy*dy + dz*dz;
        const double _r = sqrt(r2);
        const double r3inv = 1./(r2*_r);
        const double r5inv = 3.*r3inv/r2;
        const double ddx = di[0][l] - dj[0][l];
        const double ddy = di[1][l] - dj[1][l];
        const double ddz = di[2][l] - dj[2][l];
        const double dxdx = dx*dx*r5inv - r3inv;
        const double dydy = dy*dy*r5inv - r3inv;
        const double dzdz = dz*dz*r5inv - r3inv;
        const double dxdy = dx*dy*r5inv;
        const double dxdz = dx*dz*r5inv;
        const double dydz = dy*dz*r5inv;
        const double dax = ddx*dxdx + ddy*dxdy + ddz*dxdz;
        const double day = ddx*dxdy + ddy*dydy + ddz*dydz;
        const double daz = ddx*dxdz + ddy*dydz + ddz*dzdz;
        dai[0][l] += Gmj*dax - dGmj*r3inv*dx;
        dai[1][l] += Gmj*day - dGmj*r3inv*dy;
        dai[2][l] += Gmj*daz - dGmj*r3inv*dz;
        if (pull_j){
            daj[0][l] -= Gmi*dax - dGmi*r3inv*dx;
            daj[1][l] -= Gmi*day - dGmi*r3inv*dy;
            daj[2][l] -= Gmi*daz - dGmi*r3inv*dz;
        }
    }
}

// One set's pairs in lanes l0 .. l1 - 1, in REBOUND's order: the active
// pairs (i from 1, j < i), then each test particle against the active ones.
static inline __attribute__((always_inline)) void var_all_pairs(const struct reb_particle* ps,
        const struct reb_particle* pv, size_t N, size_t N_active, int pull, double G,
        const double (*restrict X)[3][LANES], const double (*restrict D)[3][LANES], double (*restrict DA)[3][LANES],
        const int l0, const int l1){
    for (size_t i=1; i<N_active; i++){
        for (size_t j=0; j<i; j++){
            var_pair_terms(X[i], X[j], D[i], D[j], DA[i], DA[j], G*ps[i].m, G*ps[j].m, G*pv[i].m, G*pv[j].m,
                    1, l0, l1);
        }
    }
    for (size_t i=N_active; i<N; i++){
        for (size_t j=0; j<N_active; j++){
            if (pull){
                var_pair_terms(X[i], X[j], D[i], D[j], DA[i], DA[j], G*ps[i].m, G*ps[j].m, G*pv[i].m, G*pv[j].m,
                        1, l0, l1);
            }else{
                var_pair_terms(X[i], X[j], D[i], D[j], DA[i], DA[j], G*ps[i].m, G*ps[j].m, G*pv[i].m, G*pv[j].m,
                        0, l0, l1);
            }
        }
    }
}

// REBOUND's variational gravity at stages k0 .. k1 of the real positions x
// and the variational positions dx, into da, in one pass over each set's
// pairs (the stages as lanes, as pfvi_gravity_stages). Each stage's sums add
// the same terms in the same order as REBOUND's routine would at that
// stage: the same bits (tests/test_gravity.py). Not finite is not checked
// here: REBOUND's path does not check these either (the tangent solve's
// change does).
PFVI_VECTOR_CLONES
void pfvi_gravity_variational_stages(const struct reb_simulation* r, struct pfvi_state* st, size_t N,
        const double (*x)[PFVI_STAGES_MAX][3], const double (*dx)[PFVI_STAGES_MAX][3],
        double (*da)[PFVI_STAGES_MAX][3], int k0, int k1){
    const struct reb_particle* const ps = r->particles;
    const double G = r->G;
    const size_t N_active = (r->N_active == SIZE_MAX) ? N : r->N_active;
    const int pull = r->testparticle_type;
    double (*restrict X)[3][LANES] = st->gravity_x;
    double (*restrict D)[3][LANES] = st->var_gravity_x;
    double (*restrict DA)[3][LANES] = st->var_gravity_a;
    stages_into_lanes(N, x, X, NULL, k0, k1);
    stages_into_lanes(st->var_N, dx, D, DA, k0, k1);
    const double (*const Xc)[3][LANES] = (const double (*)[3][LANES])X;
    for (size_t set=0; set<st->var_sets_N; set++){
        const size_t first = st->var_sets[set];
        const struct reb_particle* const pv = r->particles_var + first;
        const double (*const Dc)[3][LANES] = (const double (*)[3][LANES])(D + first);
        if (k1 < 4){
            var_all_pairs(ps, pv, N, N_active, pull, G, Xc, Dc, DA + first, 0, 4);
        }else if (k0 >= 4){
            var_all_pairs(ps, pv, N, N_active, pull, G, Xc, Dc, DA + first, 4, LANES);
        }else{
            var_all_pairs(ps, pv, N, N_active, pull, G, Xc, Dc, DA + first, 0, LANES);
        }
    }
    for (size_t v=0; v<st->var_N; v++){
        for (int k=k0; k<=k1; k++){
            da[v][k][0] = DA[v][0][k]; da[v][k][1] = DA[v][1][k]; da[v][k][2] = DA[v][2][k];
        }
    }
}

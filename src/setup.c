/* setup.c — initial particles and physics contexts of a scene.
 * Shear box (paper §5): material on a square lattice of spacing dr filling
 * [0, W] x [0, H]; ceil(2h/dr) layers of dummy particles below the base and
 * outside both side walls (the walls reach the same number of layers above
 * the material); no dummies at the top, which is a free surface. */
#include <math.h>
#include <stdlib.h>
#include <unistd.h>
#include "error.h"
#include "mpi/comm.h"
#include "sim.h"

typedef struct box_layout {
    long nx, ny, nl; /* material columns, rows; dummy layers */
    size_t n_mat, n_dum;
} box_layout;

static box_layout setup_layout(const struct scene *sc)
{
    const struct scene_geometry *g = &sc->geometry;
    box_layout b;
    b.nx = lround(g->width / g->dr);
    b.ny = lround(g->height / g->dr);
    b.nl = (long)ceil(2.0 * g->h_factor - 1e-9);
    b.n_mat = (size_t)(b.nx * b.ny);
    b.n_dum = (size_t)(b.nl * (b.nx + 2 * b.nl) + 2 * b.nl * (b.ny + b.nl));
    return b;
}

/* Exit with status 2 if the particles would not fit in this machine. */
static void setup_check_memory(const struct scene *sc, size_t n)
{
    double need = (double)n * (double)(part_bytes_per_particle() + 64); /* + grid, scratch */
    double have = (double)sysconf(_SC_PHYS_PAGES) * (double)sysconf(_SC_PAGESIZE);
    char where[512];
    if (need > 0.8 * have)
        input_error("%s: Geometry:dr: %.3g m gives %zu particles needing %.1f GiB; this machine has %.1f GiB",
                    scene_key_where(sc, "Geometry", "dr", where, sizeof where), sc->geometry.dr, n,
                    need / 1073741824.0, have / 1073741824.0);
}

static void setup_put(particles_t *p, size_t k, double x, double y, int kind, double vol)
{
    p->X0[0][k] = p->x[0][k] = (real)x;
    p->X0[1][k] = p->x[1][k] = (real)y;
    p->kind[k] = (uint8_t)kind;
    p->vol[k] = (real)vol;
    p->id[k] = (int64_t)k;
    p->psi[k] = 1;
}

void setup_particles(sim_t *s)
{
    const struct scene *sc = s->sc;
    double dr = sc->geometry.dr, vol = dr * dr;
    box_layout b = setup_layout(sc);
    setup_check_memory(sc, b.n_mat + b.n_dum);
    part_alloc(&s->p, 2, b.n_mat + b.n_dum);
    particles_t *p = &s->p;
    size_t k = 0;
    double H = b.ny * dr, split = sc->initial.split * H;
    for (long j = 0; j < b.ny; ++j)
        for (long i = 0; i < b.nx; ++i, ++k) {
            double y = (j + 0.5) * dr;
            setup_put(p, k, (i + 0.5) * dr, y, KIND_MATERIAL, vol);
            p->C[k] = (real)(y <= split ? sc->initial.C_below : sc->initial.C_above);
        }
    for (long l = 0; l < b.nl; ++l) /* base */
        for (long i = -b.nl; i < b.nx + b.nl; ++i, ++k)
            setup_put(p, k, (i + 0.5) * dr, -(l + 0.5) * dr, KIND_DUMMY, vol);
    for (long j = 0; j < b.ny + b.nl; ++j) /* side walls */
        for (long l = 0; l < b.nl; ++l) {
            setup_put(p, k++, -(l + 0.5) * dr, (j + 0.5) * dr, KIND_DUMMY, vol);
            setup_put(p, k++, (b.nx + l + 0.5) * dr, (j + 0.5) * dr, KIND_DUMMY, vol);
        }
    p->n = k;
    s->n_material = b.n_mat;
    if (fabs(H - sc->geometry.height) > 1e-6 * sc->geometry.height)
        warning("Geometry:height %.6g m is not a multiple of dr; the box is %.6g m high", sc->geometry.height, H);
}

void setup_contexts(sim_t *s)
{
    const struct scene *sc = s->sc;
    const struct scene_segregation *g = &sc->segregation;
    s->seg.k = sph_make((int)sc->geometry.dim, (real)(sc->geometry.h_factor * sc->geometry.dr),
                        (real)sc->geometry.dr);
    seg_params *sp = &s->seg.sp;
    int asym = g->flux == SEG_FLUX_ASYMMETRIC;
    sp->A = (real)(asym ? g->A : 1.0);
    sp->kappa = (real)(asym ? g->kappa : 0.0);
    sp->shear_model = g->model == SEG_MODEL_SHEAR_RATE;
    sp->V = (real)g->V, sp->D = (real)g->D;
    sp->chi_V = (real)g->chi_V, sp->chi_D = (real)g->chi_D;
    sp->d_small = (real)g->d_small, sp->d_large = (real)g->d_large;
    const double *gv = sc->physics.gravity;
    double gn = sqrt(gv[0] * gv[0] + gv[1] * gv[1] + gv[2] * gv[2]);
    for (int d = 0; d < 3; ++d) sp->ghat[d] = (real)(gv[d] / gn);
    s->seg.scheme = (int)g->scheme;
    s->seg.renorm = g->renormalize;
    s->hcsr = g->scheme != SEG_SCHEME_CONSERVATIVE;
    s->kin.type = (int)sc->kinematics.velocity;
    s->kin.gamma0 = sc->kinematics.gamma0;
    s->kin.omega = 2.0 * M_PI / sc->kinematics.period;
}

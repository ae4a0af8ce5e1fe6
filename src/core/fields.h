/* core/fields.h — the particle fields, each declared once (docs/architecture.md,
 * "The particle fields as data"). One row per field:
 *
 *   F(member, FLD, type, n, trim)
 *
 *   member  the particles_t member (src/core/particles.h); also the field's name
 *           in messages (stage_fields_str);
 *   FLD     its stage-field bit, FLD_<FLD> (src/sim/stages.h);
 *   type    element type: real, creal, preal (src/core/hd.h, which the
 *           includer brings), int64_t, uint8_t;
 *   n       components: 1 (`type *member`), 3 (`type *member[3]`: x, y, z)
 *           or 6 (`type *member[6]`: xx, yy, zz, xy, xz, yz);
 *   trim    what a trimmed 2D list keeps (stage_arrays): ALL components,
 *           VEC the x, y of a vector, SYM the xx, yy, zz, xy of a symmetric
 *           tensor.
 *
 * From the table come the members of particles_t, the store's array list
 * part_arrays[] (one array per component, in row order: alloc, free,
 * permute, pack, the GPU's copies and the checkpoints, which hold array k as
 * dataset k: the order is the checkpoints' format; do not reorder), the
 * FLD_ bits, and stage_arrays() and stage_fields_str() (src/sim/stages.c). A
 * new field is one row here (best at the end); a stage that reads or writes
 * it names FLD_<FLD> in stage_table[], a snapshot field its io_fields[] row.
 *
 * Base layer: this file includes nothing; it names only type tokens. */
#ifndef SPHSEG_CORE_FIELDS_H
#define SPHSEG_CORE_FIELDS_H

/* clang-format off */
#define PART_FIELDS(F)                                                                                       \
    F(x,      X,      real,    3, VEC) /* position, m */                                                    \
    F(X0,     X0,     real,    3, ALL) /* reference (initial) position, m, for prescribed kinematics */     \
    F(v,      V,      real,    3, VEC) /* velocity, m/s */                                                  \
    F(vol,    VOL,    real,    1, ALL) /* volume m_i/rho_i, m^d (beside DEM grains, two ways: phi / eps, \
                                        * rho the superficial density eps rho_f) */                      \
    F(C,      C,      creal,   1, ALL) /* small-grain concentration, - (double in both precisions: hd.h) */ \
    F(C_n,    CN,     creal,   1, ALL) /* C at the start of the step (predictor-corrector) */               \
    F(dCdt,   DCDT,   creal,   1, ALL) /* concentration rate, 1/s */                                        \
    F(gdot,   GDOT,   real,    1, ALL) /* shear-rate magnitude, 1/s */                                      \
    F(gsum,   GSUM,   real,    1, ALL) /* concentration windows (Segregation:every): the shear rate      \
                                        * integrated over the open window, -; divided by its length at   \
                                        * the window's concentration step, where it is the window's mean \
                                        * shear rate, 1/s */                                             \
    F(nrm,    NRM,    real,    3, VEC) /* HCSR normal, pointing into the material */                        \
    F(psi,    PSI,    real,    1, ALL) /* smoothed degenerate function psi~ (4.14, 4.18) */                  \
    F(segV,   SEGV,   real,    1, ALL) /* segregation velocity V(C, gdot), m/s, per rate evaluation */       \
    F(segQ,   SEGQ,   real,    1, ALL) /* segregation flux Q = V F(C), m/s (eq. 2.6) */                     \
    F(segD,   SEGD,   real,    1, ALL) /* diffusivity D(C, gdot), m^2/s */                                  \
    F(sig,    SIG,    real,    6, SYM) /* Cauchy stress, Pa, tension positive (material: integrated;     \
                                        * dummy: extrapolated, eq. 4.3) */                                 \
    F(sig_n,  SIGN,   real,    6, SYM) /* stress at the start of the step */                                \
    F(dsig,   DSIG,   real,    6, SYM) /* stress rate (Jaumann elastic trial rate, C1), Pa/s; also the   \
                                        * Shepard filter's scratch */                                      \
    F(x_n,    XN,     preal,   3, VEC) /* position at the start of the step, m (double in both builds) */   \
    F(xr,     XR,     real,    3, VEC) /* the single build's rounding remainder of x: the position is    \
                                        * x + xr to double precision (hd.h); 0 in the double build, m */  \
    F(v_n,    VN,     real,    3, VEC) /* velocity at the start of the step, m/s */                         \
    F(acc,    ACC,    real,    3, VEC) /* acceleration (3.9) with gravity, m/s^2 */                         \
    F(L,      L,      real,    6, ALL) /* renormalisation (-sum_j V_j w_ij x_ij x_ij)^-1, symmetric      \
                                        * (conservative scheme) */                                         \
    F(id,     ID,     int64_t, 1, ALL) /* global particle ID */                                             \
    F(kind,   KIND,   uint8_t, 1, ALL) /* enum part_kind */                                                 \
    F(bclass, BCLASS, uint8_t, 1, ALL) /* enum part_bclass */                                               \
    F(wall,   WALL,   uint8_t, 1, ALL) /* a dummy's wall (enum wall_id, src/physics/wall.h), set by     \
                                        * setup; 0 for material */                                       \
    F(B,      B,      real,    6, ALL) /* Flow:gradient_correction: the kernel gradient's correction     \
                                        * B_i (flow_kgc_store), symmetric; unused when off */            \
    F(phi,    PHI,    real,    1, ALL) /* DEM grains, two ways: a fluid particle's fluid volume eps V,   \
                                        * m^d, fixed (its mass of fluid over rho_f); 0 until its first   \
                                        * coupling sets it (dem_fluid_volume), which then gives vol =    \
                                        * phi / eps at each */
/* clang-format on */

/* The member's declarator for n components: type *member PART_FIELD_DIMS(n). */
#define PART_FIELD_DIMS(n) PART_FIELD_DIMS_##n
#define PART_FIELD_DIMS_1
#define PART_FIELD_DIMS_3 [3]
#define PART_FIELD_DIMS_6 [6]

/* G(component, type) for each component of the member in order: member
 * itself for n = 1, member[0], member[1], ... otherwise (an n other than
 * 1, 3, 6 does not compile). */
#define PART_FIELD_EACH(n, G, m, t) PART_FIELD_EACH_##n(G, m, t)
#define PART_FIELD_EACH_1(G, m, t) G(m, t)
#define PART_FIELD_EACH_3(G, m, t) G(m[0], t) G(m[1], t) G(m[2], t)
#define PART_FIELD_EACH_6(G, m, t) G(m[0], t) G(m[1], t) G(m[2], t) G(m[3], t) G(m[4], t) G(m[5], t)

/* The components a trimmed 2D list keeps of a field of n; 0 for a VEC row
 * of other than 3 or a SYM row of other than 6 (stages.c refuses it). */
#define PART_FIELD_KEEP2D(trim, n) PART_FIELD_KEEP2D_##trim(n)
#define PART_FIELD_KEEP2D_ALL(n) (n)
#define PART_FIELD_KEEP2D_VEC(n) ((n) == 3 ? 2 : 0)
#define PART_FIELD_KEEP2D_SYM(n) ((n) == 6 ? 4 : 0)

#endif

/* stage_table.h — the step's stages: each stage's id and its rows, in one
 * file (src/sim/stages.h says what follows from them). A new stage is an id
 * in enum stage_id and one row per case in stage_table[]; its body lives in
 * src/physics/ and each backend runs it under its id (src/cpu/backend_cpu.c
 * cpu_stage, gpu/gpu_step.cu gpu_hook): tests/test_counterparts.py fails on
 * an id that lacks a row or a backend's case. Included by stages.h (the
 * ids) and, with STAGE_TABLE_ROWS defined, by stages.c (the rows). */
#ifndef SPHSEG_STAGE_TABLE_IDS
#define SPHSEG_STAGE_TABLE_IDS
enum stage_id {
    ST_PLACE,        /* step_place: dummies by wall_motion / prescribed x, u, shear rate */
    ST_EXCHANGE,     /* migration, ghosts, sort (a CPU prepare; a GPU list build) */
    ST_CLASSIFY,     /* bound_classify: HCSR classes, normals, psi~ */
    ST_RENORM,       /* seg_renorm: L (the ghosts'; the owned come with the flow rates) */
    ST_WALLS,        /* flow_wall: dummy velocity and stress from the material */
    ST_FLOW,         /* flow_rates_team: acc, dsig, shear rate (+ the owned L when due) */
    ST_SEG_COEFFS,   /* seg_coeffs: V, Q, D */
    ST_DCDT,         /* seg_dCdt: dC/dt */
    ST_SAVE,         /* step_save */
    ST_ADVANCE,      /* step_advance: x, u, sigma (flow_advance) */
    ST_ADVANCE_C,    /* step_advance: C = C_n + a dC/dt */
    ST_ADVANCE_GSUM, /* step_advance: gsum += w gdot (windows) */
    ST_SHEAR_MEAN,   /* step_shear_mean: gsum / T */
    ST_WIN_RENORM,   /* seg_renorm of every material particle at the window's close */
    ST_WIN_BOUNDS,   /* step_bounds_of at the window's mean shear rate */
    ST_WIN_COEFFS,   /* seg_coeffs at the mean shear rate */
    ST_WIN_DCDT,     /* seg_dCdt at the mean shear rate */
    ST_WIN_ADVANCE,  /* step_conc_advance */
    ST_SHEPARD,      /* flow_shepard: the filtered stress into dsig */
    ST_SHEPARD_STORE, /* flow_shepard_store */
    ST_SHIFT,        /* shift_team: the shift into x_n, with v_n and sig_n carried (physics/shift.h) */
    ST_KGC,          /* flow_kgc_team: the gradient correction B of the material (physics/flow.h) */
    ST_DEM_COUPLE,   /* dem_couple: the DEM grains' coupling with the fluid (src/dem/dem.c, dem_body.h) */
    ST_CONTACT,      /* flow_contact_team: the Coulomb walls' friction on the particles (physics/flow.h) */
    ST_N
};
#endif

#ifdef STAGE_TABLE_ROWS
/* Neighbour reads of the bodies in src/physics/ (bound_gather; seg_renorm;
 * flow_wall, flow_rates_team; seg_dCdt: seg_kern.h; flow_shepard). */
#define NB_GEOM (FLD_X | FLD_VOL | FLD_KIND)
#define NB_FLOW (NB_GEOM | FLD_V | FLD_SIG)
#define NB_CONC (NB_GEOM | FLD_C | FLD_BCLASS | FLD_NRM | FLD_PSI)

/* Rows of one id share it: a stage whose reads or writes depend on the
 * run has a row per case. A row may serve several hooks (ST_WALLS). */
#define H(h) (1u << (h)) /* a hook's bit */
const stage stage_table[] = {
    /* id, hooks, body, when, unless, range, halo, writes, from_owner, reads (own: what the body reads of the
     * particle itself beyond halo; with halo and writes, the fields the run allocates: stage_store_fields) */
    {ST_PLACE, H(HOOK_PREPARE), "step_place", SF_FLOW, 0, RANGE_OWNED, 0, FLD_X | FLD_V, 0, FLD_X0 | FLD_KIND | FLD_WALL},
    {ST_PLACE, H(HOOK_PREPARE), "step_place", 0, SF_FLOW, RANGE_OWNED, 0, FLD_X | FLD_V | FLD_GDOT, 0, FLD_X0},
    /* a periodic wrap moves x with xr and x_n (hg_move) */
    {ST_EXCHANGE, H(HOOK_PREPARE), "halo_exchange, nbr_build", 0, 0, RANGE_ALL, 0, 0, 0, FLD_X | FLD_XR | FLD_XN},
    /* classes are decisions: the owners' bits, whatever a ghost's summation order */
    {ST_CLASSIFY, H(HOOK_PREPARE), "bound_classify", 0, 0, RANGE_ALL, NB_GEOM, FLD_BCLASS | FLD_NRM | FLD_PSI, 1, 0},
    /* not with windows: their dC/dt reads the L of ST_WIN_RENORM, made at the window's close */
    {ST_RENORM, H(HOOK_PREPARE), "seg_renorm", SF_SEG | SF_RENORM, SF_WIN, RANGE_ALL, NB_GEOM, FLD_L, 0, 0},
    /* each prepare: B follows the positions; the ghosts' from their own support (ghost depth 4h) */
    {ST_KGC, H(HOOK_PREPARE), "flow_kgc_team", SF_FLOW | SF_KGC, 0, RANGE_ALL, NB_GEOM, FLD_B, 0, 0},
    {ST_SHEPARD, H(HOOK_FILTER), "flow_shepard", SF_FLOW, 0, RANGE_OWNED, FLD_X | FLD_KIND | FLD_SIG, FLD_DSIG, 0,
     FLD_VOL},
    {ST_SHEPARD_STORE, H(HOOK_FILTER), "flow_shepard_store", SF_FLOW, 0, RANGE_OWNED, 0, FLD_SIG, 0, FLD_DSIG},
    /* a dummy's own wall id gives a box wall's normal */
    {ST_WALLS, H(HOOK_PREPARE) | H(HOOK_FILTER), "flow_wall", SF_FLOW, 0, RANGE_ALL, NB_FLOW | FLD_WALL,
     FLD_V | FLD_SIG, 0, 0},
    /* with SF_RENORM the owned L come with it when prepare classified: ST_RENORM's, fused */
    {ST_FLOW, H(HOOK_RATES), "flow_rates_team", SF_FLOW, 0, RANGE_OWNED, NB_FLOW, FLD_ACC | FLD_DSIG | FLD_GDOT, 0,
     FLD_C},
    {ST_FLOW, H(HOOK_RATES), "flow_rates_team", SF_FLOW | SF_KGC, 0, RANGE_OWNED, FLD_B, 0, 0, 0},
    /* Walls:coulomb_force particles: after the flow rates, the dummies' pair terms again, their tangential
     * part replaced by the friction (a dummy's B is B_i: FLD_B of i alone) */
    {ST_CONTACT, H(HOOK_RATES), "flow_contact_team", SF_FLOW | SF_CONTACT, 0, RANGE_OWNED, NB_FLOW | FLD_WALL,
     FLD_ACC, 0, FLD_ACC},
    {ST_CONTACT, H(HOOK_RATES), "flow_contact_team", SF_FLOW | SF_CONTACT | SF_KGC, 0, RANGE_OWNED, 0, 0, 0, FLD_B},
    {ST_SEG_COEFFS, H(HOOK_RATES), "seg_coeffs", SF_SEG, SF_WIN, RANGE_ALL, FLD_C | FLD_GDOT, FLD_SEGC, 0, 0},
    {ST_DCDT, H(HOOK_RATES), "seg_dCdt", SF_SEG, SF_WIN, RANGE_OWNED, NB_CONC, FLD_DCDT, 0, FLD_SEGC},
    {ST_DCDT, H(HOOK_RATES), "seg_dCdt", SF_SEG | SF_RENORM, SF_WIN, RANGE_OWNED, FLD_L, 0, 0, 0},
    {ST_SAVE, H(HOOK_SAVE), "step_save", SF_FLOW, 0, RANGE_OWNED, 0, FLD_XN | FLD_VN | FLD_SIGN, 0,
     FLD_X | FLD_XR | FLD_V | FLD_SIG},
    {ST_SAVE, H(HOOK_SAVE), "step_save", SF_SEG, 0, RANGE_OWNED, 0, FLD_CN, 0, FLD_C},
    /* after the save: it writes only the start-of-step copies, which no neighbour reads */
    {ST_SHIFT, H(HOOK_SAVE), "shift_team", SF_FLOW | SF_SHIFT, 0, RANGE_OWNED, NB_FLOW, FLD_XN | FLD_VN | FLD_SIGN, 0,
     FLD_ACC | FLD_DSIG},
    {ST_ADVANCE, H(HOOK_ADVANCE), "step_advance", SF_FLOW, 0, RANGE_OWNED, 0, FLD_X | FLD_XR | FLD_V | FLD_SIG, 0,
     FLD_KIND | FLD_XN | FLD_VN | FLD_SIGN | FLD_ACC | FLD_DSIG | FLD_GDOT | FLD_C},
    {ST_ADVANCE_C, H(HOOK_ADVANCE), "step_advance", SF_SEG, SF_WIN, RANGE_OWNED, 0, FLD_C, 0, FLD_CN | FLD_DCDT},
    {ST_ADVANCE_GSUM, H(HOOK_ADVANCE), "step_advance", SF_WIN, 0, RANGE_OWNED, 0, FLD_GSUM, 0, FLD_GDOT},
    {ST_SHEAR_MEAN, H(HOOK_CONC_BEGIN), "step_shear_mean", SF_WIN, 0, RANGE_OWNED, 0, FLD_GSUM, 0, 0},
    {ST_WIN_RENORM, H(HOOK_CONC_BEGIN), "seg_renorm", SF_WIN | SF_RENORM, 0, RANGE_ALL, NB_GEOM, FLD_L, 0, 0},
    {ST_WIN_BOUNDS, H(HOOK_CONC_BEGIN), "step_bounds_of", SF_WIN, 0, RANGE_OWNED, 0, 0, 0, FLD_C | FLD_GSUM},
    {ST_WIN_COEFFS, H(HOOK_CONC_STEP), "seg_coeffs", SF_WIN, 0, RANGE_ALL, FLD_C | FLD_GSUM, FLD_SEGC, 0, 0},
    {ST_WIN_DCDT, H(HOOK_CONC_STEP), "seg_dCdt", SF_WIN, 0, RANGE_OWNED, NB_CONC, FLD_DCDT, 0, FLD_SEGC},
    {ST_WIN_DCDT, H(HOOK_CONC_STEP), "seg_dCdt", SF_WIN | SF_RENORM, 0, RANGE_OWNED, FLD_L, 0, 0, 0},
    {ST_WIN_ADVANCE, H(HOOK_CONC_STEP), "step_conc_advance", SF_WIN, 0, RANGE_OWNED, 0, FLD_C | FLD_CN, 0, FLD_DCDT},
    /* the grains' coupling: the fluid fraction at the fluid particles (at the ghosts too, from the grains
     * every rank holds), the grains' sums over the owned ones' volumes and velocities */
    {ST_DEM_COUPLE, H(HOOK_DEM), "dem_couple", SF_DEM, 0, RANGE_OWNED, 0, 0, 0, FLD_V | FLD_VOL},
    /* two ways (computed flow: the scene's check): the owned fluid particles' volume phi / eps (phi set at
     * the first coupling) and the source into their acc and dsig; the ghosts take their volume from their
     * own eps and the phi they carry (the source's pair term reads them with their v in this pass), and
     * their owners' where the plan refreshes it before an exchange */
    {ST_DEM_COUPLE, H(HOOK_DEM), "dem_couple", SF_FLOW | SF_DEM | SF_DEM2, 0, RANGE_OWNED, FLD_V | FLD_PHI,
     FLD_VOL | FLD_PHI | FLD_ACC | FLD_DSIG, 0, 0},
};
#endif

/* test_scene.c — scene loading (src/scene*.c): the default scene, defaults,
 * -P overrides, the used-parameters echo read back bit for bit, and every
 * bad input in tests/scenes_bad/ giving one located message. Expected values
 * are written out here, independently of scene.c's tables; each bad file
 * states its expected message in its first line ("# expect: ...").
 * Run from the repository root (or build with -DSPHSEG_ROOT=\"path\"):
 *   make build/tests/test_scene && build/tests/test_scene */
#define _POSIX_C_SOURCE 200809L
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "scene/scene.h"

#ifndef SPHSEG_ROOT
#define SPHSEG_ROOT "."
#endif
#define BAD_DIR SPHSEG_ROOT "/tests/scenes_bad"
#define GOOD SPHSEG_ROOT "/inputs/shearbox_2d.yml"
#define PI 3.14159265358979323846

/* Smallest valid scene: the required keys only. */
static const char *const minimal_yaml = "Run:\n"
                                        "  t_end: 2.5\n"
                                        "Geometry:\n"
                                        "  dr: 0.002\n"
                                        "Output:\n"
                                        "  dt: 0.5\n"
                                        "Segregation:\n"
                                        "  V: 1.0e-4\n"
                                        "  D: 1.0e-6\n";

static char g_dir[64];

static char *tmp_path(const char *name)
{
    static char path[128];
    snprintf(path, sizeof path, "%s/%s", g_dir, name);
    return path;
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_true(fputs(text, f) >= 0);
    assert_int_equal(fclose(f), 0);
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    static char buf[16384];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return buf;
}

/* Parse or fail the test with the message. */
static void parse_ok(struct scene *s, const char *path, int n, const char **over)
{
    char err[SCENE_ERRLEN];
    if (scene_parse(s, path, n, (char **)over, err, sizeof err)) fail_msg("%s", err);
}

static void assert_bits(double a, double b)
{
    if (memcmp(&a, &b, sizeof a)) fail_msg("%.17g != %.17g", a, b);
}

/* ---- the default scene ------------------------------------------------------------ */

static void test_shearbox(void **state)
{
    (void)state;
    struct scene s;
    parse_ok(&s, GOOD, 0, NULL);
    double H = 0.087, g0 = tan(PI / 6), T = 13, B = H * g0;
    assert_int_equal(s.geometry.type, GEOM_SHEARBOX);
    assert_int_equal(s.geometry.dim, 2);
    assert_bits(s.geometry.height, H);
    assert_bits(s.geometry.width, 0.037);
    assert_bits(s.geometry.dr, 0.02 * H);
    assert_bits(s.geometry.h_factor, 1.5);
    assert_int_equal(s.kinematics.velocity, KIN_OSCILLATORY_SHEAR);
    assert_true(fabs(s.kinematics.gamma0 - g0) <= 1e-16);
    assert_bits(s.kinematics.period, T);
    /* eq. (5.2), written to 6 significant digits */
    assert_true(fabs(s.segregation.V / (3.0e-2 * B / T) - 1) < 5e-6);
    assert_true(fabs(s.segregation.D / (1.01e-3 * B * B / T) - 1) < 5e-6);
    assert_int_equal(s.segregation.model, SEG_MODEL_CONSTANT);
    assert_int_equal(s.segregation.flux, SEG_FLUX_SYMMETRIC);
    assert_int_equal(s.segregation.scheme, SEG_SCHEME_CONSERVATIVE);
    /* eq. (5.6) with dbar = 6 mm and gammadot_m = 4 gamma0 / T, to 2-3 digits */
    double gm = 4 * g0 / T, dbar = 0.5 * (s.grains.d_small + s.grains.d_large);
    assert_true(fabs(s.segregation.chi_V - B * 3.0e-2 / (T * gm * dbar)) < 0.005);
    assert_true(fabs(s.segregation.chi_D - B * B * 1.01e-3 / (T * gm * dbar * dbar)) < 0.0005);
    assert_bits(s.initial.C_below, 0);
    assert_bits(s.initial.C_above, 1);
    assert_bits(s.initial.split, 0.5);
    assert_bits(s.run.t_end, 80 * T);
    assert_bits(s.output.dt, T);
    assert_bits(s.output.diag_dt, 1.3);
    assert_bits(s.physics.gravity[1], -9.81);
    assert_string_equal(s.run.backend, "auto");
    assert_string_equal(s.path, GOOD);
    assert_string_equal(s.text, read_text(GOOD));
    scene_free(&s);
    assert_null(s.text);
}

static void test_defaults(void **state)
{
    (void)state;
    struct scene s;
    write_text(tmp_path("minimal.yml"), minimal_yaml);
    parse_ok(&s, tmp_path("minimal.yml"), 0, NULL);
    assert_bits(s.run.t_end, 2.5);
    assert_bits(s.run.cfl_diffusion, 0.1);
    assert_bits(s.run.cfl_segregation, 0.2);
    assert_bits(s.run.cfl_kinematic, 1.0);
    assert_bits(s.run.dt_max, 1e30);
    assert_bits(s.run.progress_s, 10);
    assert_int_equal(s.run.max_steps, 0);
    assert_bits(s.run.max_wall_time, 0);
    assert_bits(s.output.checkpoint_dt, 0);
    assert_string_equal(s.run.backend, "auto");
    assert_int_equal(s.geometry.type, GEOM_SHEARBOX);
    assert_int_equal(s.geometry.dim, 2);
    assert_bits(s.geometry.h_factor, 1.5);
    assert_bits(s.geometry.height, 0.087);
    assert_bits(s.geometry.width, 0.037);
    assert_int_equal(s.kinematics.velocity, KIN_OSCILLATORY_SHEAR);
    assert_bits(s.kinematics.gamma0, 0.5773502691896257);
    assert_true(fabs(s.kinematics.gamma0 - tan(PI / 6)) <= 1e-16);
    assert_bits(s.kinematics.period, 13);
    assert_int_equal(s.segregation.flux, SEG_FLUX_SYMMETRIC);
    assert_bits(s.segregation.A, 1.6);
    assert_bits(s.segregation.kappa, 0.89);
    assert_int_equal(s.segregation.model, SEG_MODEL_CONSTANT);
    assert_bits(s.segregation.chi_V, 0.11);
    assert_bits(s.segregation.chi_D, 0.0307);
    assert_bits(s.grains.d_small, 0.004);
    assert_bits(s.grains.d_large, 0.008);
    assert_int_equal(s.segregation.scheme, SEG_SCHEME_CONSERVATIVE);
    assert_int_equal(s.segregation.renormalize, 1);
    assert_bits(s.segregation.drift_tol, 1e-3);
    assert_bits(s.initial.C_below, 0);
    assert_bits(s.initial.C_above, 1);
    assert_bits(s.initial.split, 0.5);
    assert_bits(s.output.diag_dt, 0.5 / 20);
    assert_bits(s.physics.gravity[0], 0);
    assert_bits(s.physics.gravity[1], -9.81);
    assert_bits(s.physics.gravity[2], 0);
    assert_bits(s.physics.rho, 1500);
    scene_free(&s);
}

/* A section written with no keys is an empty section; shear_rate needs no V, D. */
static void test_empty_section(void **state)
{
    (void)state;
    struct scene s;
    write_text(tmp_path("empty_sec.yml"), "Run:\n  t_end: 1\nGeometry:\n  dr: 0.002\nOutput:\n"
                                          "  dt: 0.5\nPhysics:\n  # none\nSegregation:\n"
                                          "  model: shear_rate\n");
    parse_ok(&s, tmp_path("empty_sec.yml"), 0, NULL);
    assert_int_equal(s.segregation.model, SEG_MODEL_SHEAR_RATE);
    assert_bits(s.physics.gravity[1], -9.81);
    scene_free(&s);
}

/* ---- -P overrides -------------------------------------------------------------------- */

static void test_overrides(void **state)
{
    (void)state;
    struct scene s;
    const char *over[] = {
        "Geometry:dr=0.003",        "Physics:gravity=[0, -1.5, 0]", "Run:backend=gpu",
        "Kinematics:velocity=rest", "Initial:split=0.25",           "Segregation:flux=asymmetric",
        "Geometry:dr=0.004",        "Output:diag_dt=0.125",         "Segregation:model=shear_rate"};
    write_text(tmp_path("minimal.yml"), minimal_yaml);
    parse_ok(&s, tmp_path("minimal.yml"), 9, over);
    assert_bits(s.geometry.dr, 0.004); /* the later of two wins */
    assert_bits(s.physics.gravity[0], 0);
    assert_bits(s.physics.gravity[1], -1.5);
    assert_string_equal(s.run.backend, "gpu");
    assert_int_equal(s.kinematics.velocity, KIN_REST);
    assert_bits(s.initial.split, 0.25); /* Initial: is absent from the file */
    assert_int_equal(s.segregation.flux, SEG_FLUX_ASYMMETRIC);
    assert_int_equal(s.segregation.model, SEG_MODEL_SHEAR_RATE);
    assert_bits(s.output.diag_dt, 0.125);
    assert_bits(s.run.t_end, 2.5);             /* untouched */
    assert_string_equal(s.text, minimal_yaml); /* the file as written */
    scene_free(&s);
}

/* The grain sizes' old place, Segregation:d_small/d_large (file or -P), is
 * read as Grains (with a warning); the values land in s.grains, and the echo
 * holds them under Grains only. */
static void test_grains_old_place(void **state)
{
    (void)state;
    struct scene s;
    char text[512];
    snprintf(text, sizeof text, "%s  d_small: 0.003\n  d_large: 0.006\n", minimal_yaml);
    write_text(tmp_path("grains_old.yml"), text);
    parse_ok(&s, tmp_path("grains_old.yml"), 0, NULL);
    assert_bits(s.grains.d_small, 0.003);
    assert_bits(s.grains.d_large, 0.006);
    char *used = scene_used_text(&s);
    assert_non_null(used);
    assert_non_null(strstr(used, "Grains:\n  d_small: 0.003\n  d_large: 0.006\n"));
    assert_null(strstr(strstr(used, "Segregation:"), "d_small"));
    free(used);
    scene_free(&s);
    const char *over[] = {"Segregation:d_large=0.01"};
    write_text(tmp_path("minimal.yml"), minimal_yaml);
    parse_ok(&s, tmp_path("minimal.yml"), 1, over);
    assert_bits(s.grains.d_small, 0.004); /* the default */
    assert_bits(s.grains.d_large, 0.01);
    scene_free(&s);
}

/* Overrides apply before validation: a bad value in the file can be fixed. */
static void test_override_fixes_file(void **state)
{
    (void)state;
    struct scene s;
    const char *over[] = {"Geometry:dr=0.002"};
    parse_ok(&s, BAD_DIR "/negative_dr.yml", 1, over);
    assert_bits(s.geometry.dr, 0.002);
    scene_free(&s);
}

/* Locations kept for errors found after loading (scene_key_line/_where). */
static void test_key_where(void **state)
{
    (void)state;
    struct scene s;
    char buf[256], want[256];
    const char *over[] = {"Geometry:dr=0.003", "Initial:split=0.25"};
    write_text(tmp_path("minimal.yml"), minimal_yaml);
    parse_ok(&s, tmp_path("minimal.yml"), 2, over);
    assert_int_equal(scene_key_line(&s, "Run", "t_end"), 2);
    assert_int_equal(scene_key_line(&s, "Segregation", "D"), 9);
    assert_int_equal(scene_key_line(&s, "Geometry", "dr"), 4);     /* in the file, set by -P */
    assert_int_equal(scene_key_line(&s, "Geometry", "width"), 3);  /* a default: its section */
    assert_int_equal(scene_key_line(&s, "Physics", "gravity"), 1); /* no section in the file */
    assert_int_equal(scene_key_line(&s, "Initial", "split"), 1);   /* only given by -P */
    snprintf(want, sizeof want, "%s:2", tmp_path("minimal.yml"));
    assert_string_equal(scene_key_where(&s, "Run", "t_end", buf, sizeof buf), want);
    assert_string_equal(scene_key_where(&s, "Geometry", "dr", buf, sizeof buf), "-P Geometry:dr=0.003");
    assert_string_equal(scene_key_where(&s, "Initial", "split", buf, sizeof buf), "-P Initial:split=0.25");
    scene_free(&s);
    assert_null(s.keys);
}

/* ---- used parameters ------------------------------------------------------------------- */

static void assert_scene_equal(const struct scene *a, const struct scene *b)
{
#define EQ(f) assert_memory_equal(&a->f, &b->f, sizeof a->f)
    EQ(run.t_end), EQ(run.cfl_diffusion), EQ(run.cfl_segregation), EQ(run.cfl_kinematic);
    EQ(run.dt_max), EQ(run.progress_s), EQ(run.max_wall_time), EQ(output.checkpoint_dt);
    assert_string_equal(a->run.backend, b->run.backend);
    EQ(geometry.type), EQ(geometry.dim), EQ(geometry.dr), EQ(geometry.h_factor);
    EQ(geometry.height), EQ(geometry.width);
    EQ(kinematics.velocity), EQ(kinematics.gamma0), EQ(kinematics.period);
    EQ(segregation.flux), EQ(segregation.A), EQ(segregation.kappa), EQ(segregation.model);
    EQ(segregation.V), EQ(segregation.D), EQ(segregation.chi_V), EQ(segregation.chi_D);
    EQ(grains.d_small), EQ(grains.d_large), EQ(segregation.scheme), EQ(segregation.renormalize);
    EQ(segregation.drift_tol);
    EQ(initial.C_below), EQ(initial.C_above), EQ(initial.split);
    EQ(output.dt), EQ(output.diag_dt), EQ(physics.gravity), EQ(physics.rho);
#undef EQ
}

/* Write used_params.yml, read it back: every value bit for bit, same text. */
static void round_trip(const char *path, int n, const char **over)
{
    struct scene a, b;
    parse_ok(&a, path, n, over);
    const char *used = tmp_path("used_params.yml");
    assert_int_equal(scene_write_used(&a, used), 0);
    char tmp[160];
    snprintf(tmp, sizeof tmp, "%s.tmp", used);
    assert_int_equal(access(tmp, F_OK), -1); /* renamed away */
    parse_ok(&b, used, 0, NULL);
    assert_scene_equal(&a, &b);
    char *ta = scene_used_text(&a), *tb = scene_used_text(&b);
    assert_string_equal(ta, tb);
    assert_string_equal(ta, read_text(used));
    free(ta);
    free(tb);
    scene_free(&a);
    scene_free(&b);
}

static void test_round_trip(void **state)
{
    (void)state;
    const char *awkward[] = {"Run:t_end=0.33333333333333331",
                             "Run:dt_max=4.9406564584124654e-324",
                             "Kinematics:gamma0=0.1",
                             "Segregation:V=1.0000000000000002",
                             "Physics:gravity=[-0.0, -9.8066499999999994, 0]",
                             "Run:backend=gpu",
                             "Segregation:scheme=direct"};
    round_trip(GOOD, 0, NULL);
    round_trip(GOOD, 7, awkward);
    write_text(tmp_path("minimal.yml"), minimal_yaml);
    round_trip(tmp_path("minimal.yml"), 0, NULL);
}

static void test_write_used_fails(void **state)
{
    (void)state;
    struct scene s;
    parse_ok(&s, GOOD, 0, NULL);
    assert_int_not_equal(scene_write_used(&s, tmp_path("no/such/dir/used.yml")), 0);
    assert_int_equal(access(tmp_path("no"), F_OK), -1);
    scene_free(&s);
}

/* ---- bad input --------------------------------------------------------------------------- */

/* Parse must fail with one line containing expect (at its start if at_start),
 * leaving *s zeroed. */
static void expect_fail(const char *path, int n, const char **over, const char *expect, int at_start)
{
    struct scene s;
    char err[SCENE_ERRLEN];
    memset(&s, 0xab, sizeof s);
    int rc = scene_parse(&s, path, n, (char **)over, err, sizeof err);
    print_message("  %s\n", err);
    if (rc == 0) fail_msg("%s: parsed, expected \"%s\"", path, expect);
    const char *at = strstr(err, expect);
    if (!at || (at_start && at != err)) fail_msg("got \"%s\", expected \"%s\"", err, expect);
    assert_null(strchr(err, '\n'));
    assert_null(s.path);
    assert_null(s.text);
    assert_null(s.run.backend);
}

static const char *const bad_files[] = {
    "bad_enum.yml",        "bad_utf8.yml",    "c_above.yml",       "dim3.yml",        "duplicate_key.yml",
    "gravity_short.yml",   "inf.yml",         "kappa_one.yml",     "missing_V.yml",   "missing_run.yml",
    "missing_t_end.yml",   "nan.yml",         "negative_dr.yml",   "not_yaml.yml",    "overflow.yml",
    "section_scalar.yml",  "top_list.yml",    "two_documents.yml", "unit_suffix.yml", "unknown_key.yml",
    "unknown_section.yml", "width_small.yml", "wrong_type.yml",    "drum3d_length.yml", "grains_twice.yml",
    "grains_order.yml",    "periodic_drum.yml",   "periodic_short.yml",  "periodic_z2d.yml", "gate_negative.yml",   "outlet_above.yml",
    "container_gate_time.yml", "container_turning_segment.yml", "container_name.yml", "container_no_region.yml",
    "container_walls_in_column.yml", "container_post_segment.yml", "periodic_y_column.yml",
    "periodic_y_geostatic.yml", "dem_granular.yml", "dem_outside.yml", "dem_block_n.yml", "dem_spacing.yml",
    "dem_rest_two_way.yml", "dem_coupling.yml", "dem_periodic_short.yml", "container_no_wall.yml"};
/* (scenes_bad/setup/: errors that only building the particles finds, test_badinput.sh) */

static void test_bad_files(void **state)
{
    (void)state;
    char path[256], expect[512];
    for (size_t i = 0; i < sizeof bad_files / sizeof bad_files[0]; ++i) {
        size_t len = strlen(bad_files[i]);
        snprintf(path, sizeof path, "%s/%s", BAD_DIR, bad_files[i]);
        const char *want = read_text(path) + 10;
        assert_int_equal(strncmp(want - 10, "# expect: ", 10), 0);
        /* "NAME:LINE: ...": the message is "DIR/NAME:LINE: ..." */
        assert_int_equal(strncmp(want, bad_files[i], len), 0);
        assert_true(want[len] == ':' && want[len + 1] >= '1' && want[len + 1] <= '9');
        snprintf(expect, sizeof expect, "%s/%.*s", BAD_DIR, (int)strcspn(want, "\n"), want);
        expect_fail(path, 0, NULL, expect, 1);
    }
}

/* Every .yml in the directory is in bad_files (tests/test_badinput.sh globs). */
static void test_bad_files_listed(void **state)
{
    (void)state;
    DIR *d = opendir(BAD_DIR);
    assert_non_null(d);
    size_t n = 0;
    for (struct dirent *e; (e = readdir(d));) {
        size_t len = strlen(e->d_name);
        if (len < 4 || strcmp(e->d_name + len - 4, ".yml")) continue;
        int found = 0;
        for (size_t i = 0; i < sizeof bad_files / sizeof bad_files[0]; ++i)
            found |= !strcmp(e->d_name, bad_files[i]);
        if (!found) fail_msg("%s is not in bad_files", e->d_name);
        ++n;
    }
    closedir(d);
    assert_int_equal(n, sizeof bad_files / sizeof bad_files[0]);
}

static void test_unreadable(void **state)
{
    (void)state;
    expect_fail(BAD_DIR "/does_not_exist.yml", 0, NULL,
                BAD_DIR "/does_not_exist.yml: cannot read: No such file or directory", 1);
    expect_fail(BAD_DIR, 0, NULL, BAD_DIR ": cannot read: Is a directory", 1);
    write_text(tmp_path("empty.yml"), "");
    expect_fail(tmp_path("empty.yml"), 0, NULL, "empty.yml: the file is empty (0 bytes)", 0);
    /* comments alone, or with -P overrides: still an empty file, not a missing key (issue 55) */
    write_text(tmp_path("empty.yml"), "# a comment\n\n");
    expect_fail(tmp_path("empty.yml"), 0, NULL, "empty.yml: the file is empty (no YAML content", 0);
    const char *over[] = {"Run:t_end=1"};
    expect_fail(tmp_path("empty.yml"), 1, over, "empty.yml: the file is empty (no YAML content", 0);
}

static void test_bad_overrides(void **state)
{
    (void)state;
    static const char *const cases[][2] = {
        {"Run:foo=1", "-P Run:foo=1: Run:foo: unknown key"},
        {"Geometry:dr", "-P Geometry:dr: malformed override"},
        {"Run=1", "-P Run=1: malformed override"},
        {"=1", "-P =1: malformed override"},
        {"Run::t_end=1", "-P Run::t_end=1: malformed override"},
        {"Foo:x=1", "-P Foo:x=1: Foo: unknown section"},
        {"Run:t_end:x=1", "-P Run:t_end:x=1: Run:t_end: not a section"},
        {"Geometry:dr=-1", "-P Geometry:dr=-1: Geometry:dr: must be > 0, got -1"},
        {"Run:t_end=abc", "-P Run:t_end=abc: Run:t_end: expected a number, got 'abc'"},
        {"Run:t_end=", "-P Run:t_end=: Run:t_end: expected a number, got ''"},
        {"Run:t_end=[", "-P Run:t_end=[: value is not valid YAML"},
        {"Run:t_end=.nan", "-P Run:t_end=.nan: Run:t_end: not a finite number"},
        {"Physics:gravity=[0,0,0]", "-P Physics:gravity=[0,0,0]: Physics:gravity: must not be all"},
        {"Physics:gravity=[0,-1]", "-P Physics:gravity=[0,-1]: Physics:gravity: expected 3 entries"},
        {"Physics:gravity=&a [*a, 1, 2]", "-P Physics:gravity=&a [*a, 1, 2]: value is nested"},
        {"Run:backend=tpu", "-P Run:backend=tpu: Run:backend: expected auto, cpu or gpu, got 'tpu'"},
        {"Segregation:scheme=best", "Segregation:scheme: expected one of paper|direct|conservative"},
        {"Geometry:dim=3", "-P Geometry:dim=3: Geometry:dim: 3D is supported for Geometry:type column or drum"},
        {"Geometry:dim=-2", "Geometry:dim: expected a non-negative integer, got '-2'"},
        {"Initial:split=1.5", "-P Initial:split=1.5: Initial:split: must be in [0, 1], got 1.5"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i)
        expect_fail(GOOD, 1, (const char **)&cases[i][0], cases[i][1], cases[i][1][0] == '-');
}

/* Errors in values that were not written: at the section's line, or line 1. */
static void test_default_located(void **state)
{
    (void)state;
    const char *over[] = {"Run:cfl_kinematic=0.5"};
    write_text(tmp_path("dr_big.yml"), "Run:\n  t_end: 1\nOutput:\n  dt: 0.1\n"
                                       "Geometry:\n  dr: 0.01\nSegregation:\n  V: 0\n  D: 1e-6\n");
    expect_fail(tmp_path("dr_big.yml"), 0, NULL, "dr_big.yml:5: Geometry:width: must be >= 4*dr", 0);
    /* a section made by -P is not where a missing required key is */
    write_text(tmp_path("no_run.yml"), "Output:\n  dt: 0.1\nGeometry:\n  dr: 0.002\n"
                                       "Segregation:\n  V: 0\n  D: 1e-6\n");
    expect_fail(tmp_path("no_run.yml"), 1, over, "no_run.yml:1: Run:t_end: required key missing", 0);
}

static int setup(void **state)
{
    (void)state;
    snprintf(g_dir, sizeof g_dir, "/tmp/test_scene.XXXXXX");
    return mkdtemp(g_dir) ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    static const char *const names[] = {"minimal.yml", "empty_sec.yml", "used_params.yml",
                                        "empty.yml",   "dr_big.yml",    "no_run.yml",   "grains_old.yml"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; ++i)
        remove(tmp_path(names[i]));
    return rmdir(g_dir);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_shearbox),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_empty_section),
        cmocka_unit_test(test_overrides),
        cmocka_unit_test(test_grains_old_place),
        cmocka_unit_test(test_override_fixes_file),
        cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_write_used_fails),
        cmocka_unit_test(test_key_where),
        cmocka_unit_test(test_bad_files),
        cmocka_unit_test(test_bad_files_listed),
        cmocka_unit_test(test_unreadable),
        cmocka_unit_test(test_bad_overrides),
        cmocka_unit_test(test_default_located),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}

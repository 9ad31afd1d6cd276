/* C99: the body's material through tissue.h (issue 32). A 4 cm tet box, built here as 6 x 6
 * x 6 cells of six tetrahedra, is made of the material scheme's organ at E and at 2E; each
 * settles on its tray for 150 steps, then a probe is pressed 0.5 cm below its settled top: the
 * stiffer box sags about half as much and pushes back about twice as hard. A Poisson's ratio
 * out of range is refused naming `poisson`; the material in force reads back. Self-collision
 * (issue 35) is on by default, off through the struct's field, switched off and on again on a
 * live body. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tissue.h"

static int failures = 0;

static void check(int ok, const char *what) {
    if (!ok) {
        fprintf(stderr, "FAILED: %s\n", what);
        ++failures;
    }
}

static void ok(tissue_status s, const char *what) {
    if (s != TISSUE_OK) {
        char message[512];
        tissue_last_error(message, sizeof message);
        fprintf(stderr, "FAILED: %s gave %d: %s\n", what, (int)s, message);
        exit(1);
    }
}

#define N 6
#define SIDE 4.0f
#define NODES ((N + 1) * (N + 1) * (N + 1))
#define TETS (6 * N * N * N)

/* The box's nodes and tets: each cell cut into the six tetrahedra around its main diagonal
 * (the same split in every cell, so neighbouring faces match), tissue-mesh's `tet_box`. */
static tissue_mesh *cube(void) {
    static float xyz[3 * NODES];
    static uint32_t tets[4 * TETS];
    const uint32_t stride[3] = {1, N + 1, (N + 1) * (N + 1)};
    const int orders[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
    size_t n = 0;
    for (int k = 0; k <= N; ++k)
        for (int j = 0; j <= N; ++j)
            for (int i = 0; i <= N; ++i) {
                xyz[n++] = SIDE * (float)i / N;
                xyz[n++] = SIDE * (float)j / N;
                xyz[n++] = SIDE * (float)k / N;
            }
    n = 0;
    for (int k = 0; k < N; ++k)
        for (int j = 0; j < N; ++j)
            for (int i = 0; i < N; ++i) {
                const uint32_t v0 = i * stride[0] + j * stride[1] + k * stride[2];
                for (int o = 0; o < 6; ++o) {
                    const uint32_t v1 = v0 + stride[orders[o][0]];
                    const uint32_t v2 = v1 + stride[orders[o][1]];
                    const uint32_t v3 = v2 + stride[orders[o][2]];
                    /* Positive volumes: the odd axis orders swap their last two nodes. */
                    tets[n++] = v0;
                    tets[n++] = v1;
                    tets[n++] = o < 3 ? v2 : v3;
                    tets[n++] = o < 3 ? v3 : v2;
                }
            }
    tissue_mesh *mesh = NULL;
    ok(tissue_mesh_from_tets(xyz, NODES, tets, TETS, &mesh), "box mesh");
    return mesh;
}

/* The highest node within 0.3 cm of the vertical axis x = z = 0. */
static float top(const tissue_body *body) {
    static float xyz[3 * NODES];
    ok(tissue_body_copy_positions(body, xyz, 3 * NODES, NULL), "positions");
    float y = -1e9f;
    for (size_t i = 0; i < NODES; ++i) {
        const float *p = xyz + 3 * i;
        if (hypotf(p[0], p[2]) < 0.3f && p[1] > y) y = p[1];
    }
    return y;
}

static tissue_pose at_height(float y) {
    tissue_pose pose = {{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, y, 0.0f}};
    return pose;
}

/* The box of Young's modulus `young_kpa`: its top's sag after 150 steps (cm), then the force
 * of the tissue on a probe (radius 0.5 cm) lowered over 30 steps until its tip is 0.5 cm below
 * the settled top and held for 60 (N, up). */
static void sag_and_force(const tissue_mesh *mesh, double young_kpa, float *sag, float *force) {
    tissue_material material;
    ok(tissue_material_default(&material), "default material");
    material.young_kpa = young_kpa;
    tissue_body *body = NULL;
    ok(tissue_body_new_with_material(mesh, 1.0f, &material, &body), "body");
    tissue_material in_force;
    ok(tissue_body_get_material(body, &in_force), "material in force");
    check(in_force.scheme == TISSUE_SCHEME_MATERIAL && in_force.young_kpa == young_kpa,
          "the body reports its material");
    const float top0 = top(body);
    for (int i = 0; i < 150; ++i) ok(tissue_body_step(body, NULL), "settle");
    const float settled = top(body);
    *sag = top0 - settled;

    const float radius = 0.5f, depth = 0.5f;
    const float tip[3] = {0.0f, 0.0f, 0.0f}, end[3] = {0.0f, 3.0f, 0.0f};
    const float above = settled + radius + 0.3f, pressed = settled - depth + radius;
    const tissue_pose start = at_height(above);
    uint32_t probe = 0;
    ok(tissue_body_add_capsule(body, tip, end, radius, &start, &probe), "probe");
    for (int k = 1; k <= 90; ++k) {
        const float s = k < 30 ? (float)k / 30.0f : 1.0f;
        const tissue_pose pose = at_height(above + s * (pressed - above));
        ok(tissue_tool_set_pose(body, probe, &pose), "pose");
        ok(tissue_body_step(body, NULL), "press");
    }
    float f[3];
    ok(tissue_tool_force(body, probe, f, NULL), "force");
    *force = f[1];
    tissue_body_free(body);
}

int main(void) {
    tissue_mesh *mesh = cube();

    float sag_e, force_e, sag_2e, force_2e;
    sag_and_force(mesh, 10.0, &sag_e, &force_e);
    sag_and_force(mesh, 20.0, &sag_2e, &force_2e);
    const float sag_ratio = sag_2e / sag_e, force_ratio = force_2e / force_e;
    printf("E = 10 kPa: sag %.4f cm, probe force %.4f N; E = 20 kPa: sag %.4f cm, probe force "
           "%.4f N; sag ratio %.3f, force ratio %.3f\n",
           sag_e, force_e, sag_2e, force_2e, sag_ratio, force_ratio);
    check(sag_e > 0.0f && force_e > 0.0f, "the box sags and pushes back");
    check(sag_ratio > 0.4f && sag_ratio < 0.65f, "twice E sags about half as much");
    check(force_ratio > 1.6f && force_ratio < 2.4f, "twice E pushes back about twice as hard");

    /* A Poisson's ratio out of range: refused, naming the field; nothing is made. */
    tissue_material bad;
    ok(tissue_material_preset(TISSUE_PRESET_LIVER, &bad), "liver preset");
    bad.poisson = 0.6;
    tissue_body *body = NULL;
    const tissue_status refused = tissue_body_new_with_material(mesh, 1.0f, &bad, &body);
    char message[512];
    tissue_last_error(message, sizeof message);
    printf("poisson 0.6: status %d: %s\n", (int)refused, message);
    check(refused == TISSUE_PARAMETERS && body == NULL, "an out-of-range ratio is refused");
    check(strstr(message, "poisson") != NULL, "the message names poisson");

    /* The appendix of its own tissue's preset (bowel), and read back. */
    tissue_material bowel;
    ok(tissue_material_shipped(TISSUE_ORGAN_APPENDIX, &bowel), "the appendix's material");
    ok(tissue_body_new_shipped_with_material(TISSUE_ORGAN_APPENDIX, &bowel, &body), "appendix");
    tissue_material read;
    ok(tissue_body_get_material(body, &read), "material in force");
    check(read.scheme == bowel.scheme && read.young_kpa == bowel.young_kpa &&
              read.poisson == bowel.poisson && read.density == bowel.density &&
              read.relaxation_time == bowel.relaxation_time,
          "the appendix reports its material");
    printf("appendix: E = %.2f kPa, nu = %.3f, rho = %.2f g/cm3, tau = %.2f s\n", read.young_kpa,
           read.poisson, read.density, read.relaxation_time);

    /* Self-collision (issue 35): on in what the fill functions give and in the body made of
       it (the default), off through the field (for comparison: docs/trainer.md). */
    tissue_body_info info;
    ok(tissue_body_get_info(body, &info), "info");
    check(bowel.self_collision && read.self_collision && info.self_collision,
          "self-collision is on by default");
    tissue_material def, liver;
    ok(tissue_material_default(&def), "default material");
    ok(tissue_material_preset(TISSUE_PRESET_LIVER, &liver), "liver preset");
    check(def.self_collision && liver.self_collision, "every fill function gives it on");
    tissue_body_free(body);
    body = NULL;
    /* Off through the field. */
    bowel.self_collision = false;
    ok(tissue_body_new_shipped_with_material(TISSUE_ORGAN_APPENDIX, &bowel, &body), "appendix");
    for (int i = 0; i < 5; ++i) ok(tissue_body_step(body, NULL), "step");
    ok(tissue_body_get_material(body, &read), "material in force");
    ok(tissue_body_get_info(body, &info), "info");
    check(!read.self_collision && !info.self_collision && info.self_contacts == 0,
          "self-collision off through the field");
    tissue_body_free(body);
    body = NULL;
    /* On through the field (as the fill functions give it), then switched live. */
    bowel.self_collision = true;
    ok(tissue_body_new_shipped_with_material(TISSUE_ORGAN_APPENDIX, &bowel, &body), "appendix");
    for (int i = 0; i < 5; ++i) ok(tissue_body_step(body, NULL), "step");
    ok(tissue_body_get_material(body, &read), "material in force");
    ok(tissue_body_get_info(body, &info), "info");
    check(read.self_collision && info.self_collision, "self-collision on through the field");
    /* Switched off in the live body: it says so and finds no self-contacts. */
    ok(tissue_body_set_self_collision(body, false), "self-collision off");
    for (int i = 0; i < 5; ++i) ok(tissue_body_step(body, NULL), "step");
    ok(tissue_body_get_material(body, &read), "material in force");
    ok(tissue_body_get_info(body, &info), "info");
    check(!read.self_collision && !info.self_collision && info.self_contacts == 0 &&
              info.self_contacts_active == 0,
          "self-collision switched off live");
    /* Switched on again in the live body. */
    ok(tissue_body_set_self_collision(body, true), "self-collision on");
    for (int i = 0; i < 5; ++i) ok(tissue_body_step(body, NULL), "step");
    ok(tissue_body_get_material(body, &read), "material in force");
    ok(tissue_body_get_info(body, &info), "info");
    check(read.self_collision && info.self_collision, "self-collision switched on live");
    uint64_t crossing = 1;
    ok(tissue_body_self_intersections(body, &crossing), "self-intersections");
    printf("appendix: %llu self-contacts (%llu active), %llu self-intersections\n",
           (unsigned long long)info.self_contacts, (unsigned long long)info.self_contacts_active,
           (unsigned long long)crossing);
    check(crossing == 0, "the appendix at rest does not pass through itself");
    check(tissue_body_self_intersections(body, NULL) == TISSUE_NULL_ARGUMENT,
          "a NULL count is refused");
    tissue_body_free(body);

    tissue_mesh_free(mesh);
    printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
}

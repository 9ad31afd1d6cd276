/* C99: plan Table 2 through tissue.h and check the gain against the thesis's band; read the
 * report and the deformed patient; the blocking run whose callback cancels; meshes from a file
 * and from arrays; error paths with their messages; a caught panic.
 * Usage: plan PLANE_OBJ TET_MSH (fixtures/plane_20cm_65.obj, fixtures/tets/box_v41_ascii.msh). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tissue.h"

static int failures = 0;

#define CHECK(cond, ...)                                                                          \
    do {                                                                                          \
        if (!(cond)) {                                                                            \
            fprintf(stderr, "FAILED %s:%d: %s: ", __FILE__, __LINE__, #cond);                    \
            fprintf(stderr, __VA_ARGS__);                                                         \
            fprintf(stderr, "\n");                                                                \
            failures++;                                                                           \
        }                                                                                         \
    } while (0)

/* The last error on this thread, in a buffer sized by a first query. */
static char *last_error(void) {
    size_t n = tissue_last_error(NULL, 0);
    char *text = malloc(n > 0 ? n : 1);
    text[0] = '\0';
    if (n > 0) {
        tissue_last_error(text, n);
    }
    return text;
}

#define OK(call)                                                                                  \
    do {                                                                                          \
        tissue_status s_ = (call);                                                                \
        if (s_ != TISSUE_OK) {                                                                    \
            char *e_ = last_error();                                                              \
            fprintf(stderr, "FAILED %s:%d: %s gave %d: %s\n", __FILE__, __LINE__, #call, (int)s_, \
                    e_);                                                                          \
            free(e_);                                                                             \
            exit(1);                                                                              \
        }                                                                                         \
    } while (0)

struct cancel_after {
    uint64_t steps;
    int calls;
    uint64_t last_step;
};

static int cancel_after_steps(const tissue_progress *p, void *user) {
    struct cancel_after *c = (struct cancel_after *)user;
    c->calls++;
    c->last_step = p->step;
    return p->step >= c->steps ? 1 : 0;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: plan PLANE_OBJ TET_MSH\n");
        return 2;
    }
    printf("tissue %s\n", tissue_version());

    /* --- Table 2: the default request on the shipped plane, started, polled, waited for. */
    tissue_patient *plane = NULL;
    OK(tissue_patient_shipped(TISSUE_PATIENT_TABLE2, &plane));
    tissue_plan_options options;
    OK(tissue_plan_options_default(&options));
    CHECK(options.volume_cm3 == 100.0 && options.diameter_cm == 7.0f, "defaults are Table 2's");
    tissue_job *job = NULL;
    OK(tissue_plan_start(plane, &options, &job));
    tissue_progress progress;
    int polls = 0;
    uint64_t highest = 0;
    while (tissue_job_wait(job, 0.02) == TISSUE_TIMEOUT) {
        OK(tissue_job_progress(job, &progress));
        CHECK(progress.state == TISSUE_JOB_RUNNING, "running while waiting");
        if (progress.step > highest) {
            highest = progress.step;
        }
        polls++;
    }
    OK(tissue_job_wait(job, -1.0));
    OK(tissue_job_progress(job, &progress));
    CHECK(progress.state == TISSUE_JOB_FINISHED, "state %d", (int)progress.state);
    tissue_plan_result r;
    OK(tissue_job_result(job, &r));
    printf("Table 2, 100 cm3: gain %.2f cm2 (thesis 31.43, band 23.6-39.3), volume difference "
           "%.2f cm3, %llu steps, settled %d, %.3f s stepping; %d polls saw up to step %llu\n",
           r.area_gain_cm2, r.volume_difference_cm3, (unsigned long long)r.steps, (int)r.settled,
           r.wall_time_s, polls, (unsigned long long)highest);
    CHECK(r.area_gain_cm2 >= 0.75 * 31.43 && r.area_gain_cm2 <= 1.25 * 31.43, "gain %.3f",
          r.area_gain_cm2);
    CHECK(r.volume_difference_cm3 >= 100.0 && r.volume_difference_cm3 <= 115.0, "volume %.3f",
          r.volume_difference_cm3);
    CHECK(r.settled && r.boundary_unchanged && r.max_penetration_cm == 0.0, "invariants");
    CHECK(r.region_radius_cm == 5.25, "radius %f", r.region_radius_cm);

    /* The report: query its size, then copy. */
    size_t length = 0;
    CHECK(tissue_job_report_json(job, NULL, 0, &length) == TISSUE_BUFFER_TOO_SMALL, "query");
    CHECK(length > 100, "report length %zu", length);
    char *report = malloc(length);
    OK(tissue_job_report_json(job, report, length, &length));
    CHECK(strlen(report) + 1 == length, "NUL-terminated");
    CHECK(strstr(report, "\"tool\": \"capi\"") != NULL, "tool");
    CHECK(strstr(report, "\"schema_version\": 1") != NULL, "schema");
    CHECK(strstr(report, "\"area_gain_cm2\"") != NULL, "gain in the report");
    free(report);

    /* The deformed patient: the plane's 4225 vertices, raised in the middle. */
    tissue_mesh *after = NULL;
    OK(tissue_job_patient_after(job, &after));
    tissue_mesh_kind kind;
    size_t vertices = 0, triangles = 0;
    OK(tissue_mesh_sizes(after, &kind, &vertices, &triangles));
    CHECK(kind == TISSUE_MESH_SURFACE && vertices == 65 * 65 && triangles == 2 * 64 * 64,
          "%zu vertices", vertices);
    float *xyz = malloc(3 * vertices * sizeof(float));
    CHECK(tissue_mesh_copy_positions(after, xyz, 3 * vertices - 1) == TISSUE_BUFFER_TOO_SMALL,
          "a short buffer is refused");
    OK(tissue_mesh_copy_positions(after, xyz, 3 * vertices));
    float top = 0.0f;
    for (size_t i = 0; i < vertices; i++) {
        if (xyz[3 * i + 2] > top) {
            top = xyz[3 * i + 2];
        }
    }
    float *displacement = malloc(vertices * sizeof(float));
    OK(tissue_job_copy_field(job, TISSUE_FIELD_DISPLACEMENT, displacement, vertices));
    float most = 0.0f;
    for (size_t i = 0; i < vertices; i++) {
        most = displacement[i] > most ? displacement[i] : most;
    }
    printf("the skin rose to z = %.2f cm; largest displacement %.2f cm (report %.2f)\n", top,
           most, r.max_displacement_cm);
    CHECK(top > 1.0f && most > 1.0f, "the skin rose");
    free(displacement);
    free(xyz);
    tissue_mesh_free(after);
    tissue_job_free(job);

    /* --- The blocking run: the callback cancels after 40 steps. */
    struct cancel_after c = {40, 0, 0};
    job = NULL;
    tissue_status s = tissue_plan_run(plane, &options, cancel_after_steps, &c, &job);
    char *e = last_error();
    printf("blocking run: status %d after %d callbacks (last step %llu): %s\n", (int)s, c.calls,
           (unsigned long long)c.last_step, e);
    CHECK(s == TISSUE_CANCELLED, "status %d", (int)s);
    CHECK(strstr(e, "cancelled") != NULL, "message: %s", e);
    free(e);
    OK(tissue_job_progress(job, &progress));
    CHECK(progress.state == TISSUE_JOB_CANCELLED, "state %d", (int)progress.state);
    CHECK(tissue_job_result(job, &r) == TISSUE_CANCELLED, "no result after a cancel");
    tissue_job_free(job);

    /* --- Errors: a negative volume names its field; a vertex out of range; NULLs; bad JSON. */
    options.volume_cm3 = -5.0;
    job = NULL;
    s = tissue_plan_start(plane, &options, &job);
    e = last_error();
    printf("volume -5: status %d: %s\n", (int)s, e);
    CHECK(s == TISSUE_PARAMETERS && job == NULL, "status %d", (int)s);
    CHECK(strstr(e, "volume_cm3") != NULL, "message: %s", e);
    free(e);
    OK(tissue_plan_options_default(&options));
    options.placement = TISSUE_PLACE_VERTEX;
    options.vertex = 99999;
    s = tissue_plan_start(plane, &options, &job);
    e = last_error();
    CHECK(s == TISSUE_PLACEMENT && strstr(e, "out of range") != NULL, "%d: %s", (int)s, e);
    free(e);
    options.placement = 7;
    CHECK(tissue_plan_start(plane, &options, &job) == TISSUE_INVALID_ARGUMENT, "bad enum");
    CHECK(tissue_plan_start(NULL, &options, &job) == TISSUE_NULL_ARGUMENT, "NULL patient");
    e = last_error();
    CHECK(strstr(e, "patient") != NULL, "%s", e);
    free(e);
    s = tissue_job_start_json(plane, "{\"request\": {\"volume\": 3}}", &job);
    e = last_error();
    printf("unknown JSON field: status %d: %s\n", (int)s, e);
    CHECK(s == TISSUE_USAGE && strstr(e, "volume") != NULL, "%d: %s", (int)s, e);
    free(e);
    /* Success clears the message. */
    OK(tissue_plan_options_default(&options));
    CHECK(tissue_last_error(NULL, 0) == 0, "cleared");
    /* A truncated copy still ends in NUL and says how much was needed. */
    tissue_patient *missing = NULL;
    s = tissue_patient_load("/no/such/scan.obj", TISSUE_UNIT_MM, &missing);
    char small[8];
    size_t needed = tissue_last_error(small, sizeof small);
    CHECK(s == TISSUE_INPUT && missing == NULL, "status %d", (int)s);
    CHECK(needed > sizeof small && strlen(small) == sizeof small - 1, "truncated");

    /* --- Meshes: a file of each kind, and the caller's arrays. */
    tissue_mesh *m = NULL;
    OK(tissue_mesh_load(argv[1], &m));
    OK(tissue_mesh_sizes(m, &kind, &vertices, &triangles));
    CHECK(kind == TISSUE_MESH_SURFACE && vertices == 65 * 65, "plane file");
    tissue_patient *from_file = NULL;
    OK(tissue_patient_from_mesh(m, TISSUE_UNIT_CM, "plane_20cm_65.obj", &from_file));
    tissue_patient_free(from_file);
    tissue_mesh_free(m);
    OK(tissue_mesh_load(argv[2], &m));
    size_t tets = 0;
    OK(tissue_mesh_sizes(m, &kind, &vertices, &tets));
    CHECK(kind == TISSUE_MESH_TETS && tets > 0, "tet file: %zu tets", tets);
    uint32_t *idx = malloc(4 * tets * sizeof(uint32_t));
    OK(tissue_mesh_copy_indices(m, idx, 4 * tets));
    free(idx);
    tissue_mesh_free(m);
    const float square[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const uint32_t two[] = {0, 1, 2, 0, 2, 3};
    OK(tissue_mesh_from_triangles(square, 4, two, 2, &m));
    float back[12];
    OK(tissue_mesh_copy_positions(m, back, 12));
    CHECK(memcmp(back, square, sizeof square) == 0, "positions read back");
    tissue_mesh_free(m);
    const uint32_t bad[] = {0, 1, 2, 0, 2, 9};
    m = NULL;
    s = tissue_mesh_from_triangles(square, 4, bad, 2, &m);
    e = last_error();
    printf("index 9 of 4 vertices: status %d: %s\n", (int)s, e);
    CHECK(s == TISSUE_INVALID_MESH && m == NULL, "status %d", (int)s);
    free(e);
    tissue_mesh_free(NULL);
    tissue_patient_free(NULL);
    tissue_job_free(NULL);
    tissue_body_free(NULL);

    /* --- A panic inside the library comes back as TISSUE_PANIC, with its message. */
    s = tissue_debug_panic();
    e = last_error();
    printf("caught panic: status %d: %s\n", (int)s, e);
    CHECK(s == TISSUE_PANIC && strstr(e, "panicked") != NULL, "%d: %s", (int)s, e);
    free(e);
    /* The library still works after it. */
    OK(tissue_plan_options_default(&options));

    tissue_patient_free(plane);
    printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
}

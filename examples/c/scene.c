/* weft from C, the whole scene: a world from scene text, a sphere and a floor mesh added as
 * obstacles, self-collision on, uneven frames advanced with interpolation, positions, normals
 * and triangles read back, a snapshot restored bit for bit, and errors returned as codes.
 *
 * Built and run by tests/capi.rs:
 *   cargo rustc --lib --features capi --crate-type staticlib
 *   cc examples/c/scene.c -Iinclude target/debug/libweft.a -lpthread -ldl -lm -o scene
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "weft.h"

#define CHECK(call)                                                                             \
    do {                                                                                        \
        WeftStatus s_ = (call);                                                                 \
        if (s_ != WEFT_STATUS_OK) {                                                             \
            fprintf(stderr, "%s failed (%d): %s\n", #call, (int)s_, weft_last_error_message()); \
            return 1;                                                                           \
        }                                                                                       \
    } while (0)

#define EXPECT(call, status)                                                                          \
    do {                                                                                              \
        WeftStatus s_ = (call);                                                                       \
        if (s_ != (status)) {                                                                         \
            fprintf(stderr, "%s gave %d, expected %d (%s)\n", #call, (int)s_, (int)(status),          \
                    weft_last_error_message());                                                       \
            return 1;                                                                                 \
        }                                                                                             \
        printf("%s -> %d: %s\n", #status, (int)s_, weft_last_error_message());                        \
    } while (0)

/* A horizontal cotton sheet 0.57 m square, 0.1 m above a ball. */
static const char SCENE[] =
    "[solver]\n"
    "dt = 0.016666667\n"
    "substeps = 8\n"
    "[effects]\n"
    "gravity = [0.0, -9.81, 0.0]\n"
    "[[cloth]]\n"
    "rows = 20\n"
    "cols = 20\n"
    "spacing = 0.03\n"
    "origin = [-0.285, 0.6, -0.285]\n"
    "u = [1.0, 0.0, 0.0]\n"
    "v = [0.0, 0.0, 1.0]\n"
    "fabric = \"cotton\"\n"
    "thickness = 0.01\n";

static const float SPHERE_C[3] = {0.0f, 0.3f, 0.0f};
static const float SPHERE_R = 0.2f;

int main(void) {
    WeftWorld *world = NULL;
    CHECK(weft_world_create_from_scene(SCENE, strlen(SCENE), &world));

    /* Obstacles: a ball, and a floor as a two-triangle mesh (normal +y). */
    uint32_t sphere = 99, floor_mesh = 99;
    CHECK(weft_world_add_sphere(world, SPHERE_C, SPHERE_R, NULL, &sphere));
    const float floor_v[12] = {-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2};
    const uint32_t floor_i[6] = {0, 2, 1, 0, 3, 2};
    WeftObstacleOptions slippery = {{0.0f, 0.0f, 0.0f}, true, 0.1f};
    CHECK(weft_world_add_mesh(world, floor_v, 12, floor_i, 6, WEFT_MESH_BROADPHASE_BVH, false, &slippery, &floor_mesh));
    CHECK(weft_world_set_friction(world, 0.5f));

    WeftSelfCollision sc = weft_self_collision_default();
    sc.response = WEFT_RESPONSE_VCCPBD;
    sc.broadphase = WEFT_SELF_BROADPHASE_HASH;
    CHECK(weft_world_set_self_collision(world, &sc));

    size_t n = 0, nt = 0;
    CHECK(weft_world_particle_count(world, &n));
    CHECK(weft_world_triangle_count(world, &nt));
    float *pos = malloc(3 * n * sizeof(float));
    float *prev = malloc(3 * n * sizeof(float));
    float *lerp = malloc(3 * n * sizeof(float));
    float *nrm = malloc(3 * n * sizeof(float));
    float *again = malloc(3 * n * sizeof(float));
    uint32_t *tri = malloc(3 * nt * sizeof(uint32_t));
    if (!pos || !prev || !lerp || !nrm || !again || !tri) return 1;

    /* Uneven frames (50 and 70 Hz): fixed steps of the scene's dt, interpolated for display. */
    WeftSnapshot *snap = NULL;
    uint64_t snap_steps = 0;
    int lerp_ok = 1;
    for (int frame = 0; frame < 90; frame++) {
        if (frame == 60) {
            CHECK(weft_world_snapshot(world, &snap));
            CHECK(weft_world_steps(world, &snap_steps));
        }
        CHECK(weft_world_copy_positions(world, prev, 3 * n));
        WeftAdvanceReport r;
        CHECK(weft_world_advance(world, frame % 2 ? 1.0 / 70.0 : 1.0 / 50.0, &r));
        CHECK(weft_world_copy_positions(world, pos, 3 * n));
        CHECK(weft_world_copy_interpolated_positions(world, r.alpha, lerp, 3 * n));
        /* After a one-step frame the display lies between the state before and after it. */
        for (size_t k = 0; r.steps == 1 && k < 3 * n; k++) {
            float lo = fminf(prev[k], pos[k]), hi = fmaxf(prev[k], pos[k]);
            if (lerp[k] < lo || lerp[k] > hi) lerp_ok = 0;
        }
    }
    uint64_t steps = 0;
    CHECK(weft_world_steps(world, &steps));

    /* The sheet rests on the ball: nothing inside it or under the floor, the middle held up. */
    float min_y = 1e9f, min_d = 1e9f;
    for (size_t i = 0; i < n; i++) {
        float dx = pos[3 * i] - SPHERE_C[0], dy = pos[3 * i + 1] - SPHERE_C[1], dz = pos[3 * i + 2] - SPHERE_C[2];
        min_d = fminf(min_d, sqrtf(dx * dx + dy * dy + dz * dz));
        min_y = fminf(min_y, pos[3 * i + 1]);
    }
    size_t mid = 10 * 20 + 10;
    float mid_y = pos[3 * mid + 1], corner_y = pos[1];
    printf("particles %zu, triangles %zu, steps %llu, mid y %.4f, corner y %.4f, nearest to ball centre %.4f, lowest y %.4f\n",
           n, nt, (unsigned long long)steps, mid_y, corner_y, min_d, min_y);
    int drape_ok = min_d > SPHERE_R && min_y > 0.0f && mid_y > 0.5f && corner_y < mid_y - 0.1f;

    /* Normals are unit vectors; triangles index real particles. */
    CHECK(weft_world_copy_normals(world, nrm, 3 * n));
    CHECK(weft_world_copy_triangles(world, tri, 3 * nt));
    int mesh_ok = nt == 2 * 19 * 19;
    for (size_t i = 0; i < n; i++) {
        float l = sqrtf(nrm[3 * i] * nrm[3 * i] + nrm[3 * i + 1] * nrm[3 * i + 1] + nrm[3 * i + 2] * nrm[3 * i + 2]);
        if (fabsf(l - 1.0f) > 1e-4f) mesh_ok = 0;
    }
    for (size_t k = 0; k < 3 * nt; k++)
        if (tri[k] >= n) mesh_ok = 0;
    printf("mid normal (%.3f %.3f %.3f)\n", nrm[3 * mid], nrm[3 * mid + 1], nrm[3 * mid + 2]);

    /* Back to frame 60 and the same 30 frames again: the same bits. */
    CHECK(weft_world_restore(world, snap));
    uint64_t back = 0;
    CHECK(weft_world_steps(world, &back));
    for (int frame = 60; frame < 90; frame++) CHECK(weft_world_advance(world, frame % 2 ? 1.0 / 70.0 : 1.0 / 50.0, NULL));
    CHECK(weft_world_copy_positions(world, again, 3 * n));
    int replay_ok = back == snap_steps && memcmp(again, pos, 3 * n * sizeof(float)) == 0;
    printf("snapshot at step %llu, restored to %llu, replay %s\n", (unsigned long long)snap_steps,
           (unsigned long long)back, replay_ok ? "identical" : "DIFFERENT");

    /* Errors, not crashes. */
    const char bad_scene[] = "[solver]\ndt = -1.0\n";
    WeftWorld *none = (WeftWorld *)1;
    EXPECT(weft_world_create_from_scene(bad_scene, strlen(bad_scene), &none), WEFT_STATUS_SCENE);
    if (none != NULL) return 2;
    const uint32_t bad_i[3] = {0, 1, 7};
    EXPECT(weft_world_add_mesh(world, floor_v, 12, bad_i, 3, WEFT_MESH_BROADPHASE_GRID, false, NULL, NULL), WEFT_STATUS_INVALID_MESH);
    EXPECT(weft_world_add_mesh(world, floor_v, 11, floor_i, 6, WEFT_MESH_BROADPHASE_GRID, false, NULL, NULL), WEFT_STATUS_BUFFER_LENGTH);
    EXPECT(weft_world_add_sphere(world, SPHERE_C, -1.0f, NULL, NULL), WEFT_STATUS_INVALID_ARGUMENT);
    sc.response = 7;
    EXPECT(weft_world_set_self_collision(world, &sc), WEFT_STATUS_INVALID_ARGUMENT);
    EXPECT(weft_world_copy_normals(world, nrm, 3 * n - 3), WEFT_STATUS_BUFFER_LENGTH);
    EXPECT(weft_world_copy_triangles(world, NULL, 3 * nt), WEFT_STATUS_NULL_POINTER);
    EXPECT(weft_world_advance(world, -1.0, NULL), WEFT_STATUS_INVALID_ARGUMENT);
    CHECK(weft_snapshot_destroy(snap));
    EXPECT(weft_world_restore(world, snap), WEFT_STATUS_INVALID_HANDLE);
    EXPECT(weft_snapshot_destroy(snap), WEFT_STATUS_INVALID_HANDLE);

    free(pos);
    free(prev);
    free(lerp);
    free(nrm);
    free(again);
    free(tri);
    CHECK(weft_world_destroy(world));

    printf("drape %s, interpolation %s, normals and triangles %s, replay %s\n", drape_ok ? "ok" : "FAIL",
           lerp_ok ? "ok" : "FAIL", mesh_ok ? "ok" : "FAIL", replay_ok ? "ok" : "FAIL");
    if (!(drape_ok && lerp_ok && mesh_ok && replay_ok)) return 3;
    printf("ok: scene, obstacles, self-collision, advance, readback and snapshot\n");
    return 0;
}

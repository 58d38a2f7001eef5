/* weft from C: create a world, add a hanging cloth, step it, read positions, move a pin,
 * and show that bad input returns an error code with a message instead of crashing.
 *
 * Built and run by tests/capi.rs:
 *   cargo rustc --lib --features capi --crate-type staticlib
 *   cc examples/c/cloth.c -Iinclude target/debug/libweft.a -lpthread -ldl -lm -o cloth
 */
#include <stdio.h>
#include <stdlib.h>

#include "weft.h"

#define CHECK(call)                                                                   \
    do {                                                                              \
        WeftStatus s_ = (call);                                                       \
        if (s_ != WEFT_STATUS_OK) {                                                   \
            fprintf(stderr, "%s failed (%d): %s\n", #call, (int)s_, weft_last_error_message()); \
            return 1;                                                                 \
        }                                                                             \
    } while (0)

int main(void) {
    WeftSolverParams params = weft_solver_params_default();
    params.substeps = 8;
    const float gravity[3] = {0.0f, -9.81f, 0.0f};
    WeftWorld *world = NULL;
    CHECK(weft_world_create(&params, gravity, &world));

    const float origin[3] = {0.0f, 1.0f, 0.0f};
    uint32_t cloth = 99;
    CHECK(weft_world_add_cloth(world, 16, 12, 0.05f, origin, "cotton", true, &cloth));

    size_t n = 0;
    CHECK(weft_world_particle_count(world, &n));
    float *pos = malloc(3 * n * sizeof(float));
    if (pos == NULL) return 1;
    CHECK(weft_world_copy_positions(world, pos, 3 * n));
    float y0 = pos[3 * (n - 1) + 1];

    for (int k = 0; k < 60; k++) {
        /* Drag the first pinned corner 1 mm along +x per step. */
        CHECK(weft_world_set_pin_position(world, 0, 0.001f * (float)(k + 1), 1.0f, 0.0f));
        CHECK(weft_world_step(world, params.dt));
    }
    CHECK(weft_world_copy_positions(world, pos, 3 * n));
    float y1 = pos[3 * (n - 1) + 1];
    printf("particles %zu, cloth %u, last particle y %.4f -> %.4f, pin x %.4f\n", n, cloth, y0, y1, pos[0]);

    /* Errors, not crashes. */
    WeftStatus s = weft_world_copy_positions(world, pos, 3 * n - 1);
    printf("short buffer: status %d, message: %s\n", (int)s, weft_last_error_message());
    if (s != WEFT_STATUS_BUFFER_LENGTH) return 2;
    if (weft_world_step(NULL, 0.01f) != WEFT_STATUS_INVALID_HANDLE) return 3;
    if (weft_world_step(world, -1.0f) != WEFT_STATUS_INVALID_ARGUMENT) return 4;
    if (weft_world_add_cloth(world, 4, 4, 0.1f, origin, "silk", false, NULL) != WEFT_STATUS_INVALID_ARGUMENT) return 5;
    printf("unknown preset: %s\n", weft_last_error_message());
    if (weft_world_copy_positions(world, NULL, 3 * n) != WEFT_STATUS_NULL_POINTER) return 6;

    int moved = y1 < y0 && pos[0] > 0.059f && pos[0] < 0.061f;
    free(pos);
    CHECK(weft_world_destroy(world));
    if (weft_world_destroy(world) != WEFT_STATUS_INVALID_HANDLE) return 7; /* double free caught */

    printf(moved ? "ok: the cloth fell and the pin moved\n" : "FAIL\n");
    return moved ? 0 : 8;
}

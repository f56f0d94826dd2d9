/* emm_hilbert3 (runtime/generate_surface.c), the 3D Hilbert order of the
 * generator's `hilbert` surfaces and of the synthetic patterns over meshes
 * with depth: at orders 1 to 5 it numbers every cell of the cube once, and
 * cells with consecutive numbers share a face (the curve never jumps). */
#include <stdlib.h>

#include "check.h"
#include "generate.h"

int main(void)
{
    for (int bits = 1; bits <= 5; bits++) {
        uint32_t side = 1u << bits;
        size_t cells = (size_t)side * side * side;
        uint32_t *at = malloc(cells * 3 * sizeof *at); /* the cell of each number */
        unsigned char *hit = calloc(cells, 1);
        REQUIRE(at && hit);
        for (uint32_t x = 0; x < side; x++)
            for (uint32_t y = 0; y < side; y++)
                for (uint32_t z = 0; z < side; z++) {
                    uint32_t q[3] = {x, y, z};
                    uint64_t d = emm_hilbert3(q, bits);
                    REQUIRE(d < cells);
                    CHECKF(!hit[d], "order %d: number %llu twice", bits, (unsigned long long)d);
                    hit[d] = 1;
                    at[3 * d] = x, at[3 * d + 1] = y, at[3 * d + 2] = z;
                }
        size_t jumps = 0;
        for (size_t d = 1; d < cells; d++) {
            uint32_t dist = 0;
            for (int i = 0; i < 3; i++)
                dist += at[3 * d + i] > at[3 * (d - 1) + i] ? at[3 * d + i] - at[3 * (d - 1) + i]
                                                            : at[3 * (d - 1) + i] - at[3 * d + i];
            jumps += dist != 1;
        }
        CHECKF(jumps == 0, "order %d: %zu steps between cells that share no face", bits, jumps);
        free(at);
        free(hit);
    }
    return check_done();
}

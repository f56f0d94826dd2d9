/* Geometry every layer shares (geom.h). */
#include "geom.h"

void emm_axes_largest(const double lo[3], const double hi[3], uint32_t dims, int *axes)
{
    int order[3] = {0, 1, 2};
    /* Largest extent first; of equal extents the lower axis stays ahead. */
    for (int i = 0; i < 3; i++)
        for (int j = i + 1; j < 3; j++)
            if (hi[order[j]] - lo[order[j]] > hi[order[i]] - lo[order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (uint32_t k = 0; k < dims; k++)
        axes[k] = order[k];
    for (uint32_t i = 0; i < dims; i++) /* ascending */
        for (uint32_t j = i + 1; j < dims; j++)
            if (axes[j] < axes[i]) {
                int t = axes[i];
                axes[i] = axes[j];
                axes[j] = t;
            }
}

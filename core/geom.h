/* Internal: geometry every layer shares. */
#ifndef EMM_INTERNAL_GEOM_H
#define EMM_INTERNAL_GEOM_H

#include <stdint.h>

/* The `dims` axes (0 x, 1 y, 2 z; dims <= 3) along which the box [lo, hi]
 * is largest, in ascending order; of equal extents the lower axis goes
 * first, so a planar mesh in x and y keeps x and y. The layouts, the
 * profile and the synthetic traces all see a mesh through this one choice. */
void emm_axes_largest(const double lo[3], const double hi[3], uint32_t dims, int *axes);

#endif

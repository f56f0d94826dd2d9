/* A window that reads on until it has filled the local store: window_fill.h. */
#include "window_fill.h"

#include <stdlib.h>

#include "emm/profile.h"

uint64_t emm_profile_fill_most(uint64_t window)
{
    double most = (double)window * EMM_PROFILE_FILL_REACH;
    return most < 0x1p63 ? (uint64_t)most : UINT64_MAX / 2;
}

void window_fill_start(window_fill *f, uint64_t bytes)
{
    window_fill_free(f);
    f->bytes = bytes;
}

void window_fill_size(window_fill *f, uint64_t mesh_bytes)
{
    if (mesh_bytes <= f->bytes)
        f->bytes = f->touched = 0;
}

/* The key of an element: its array in the top bits, never 0. */
static uint64_t fill_key(uint32_t array, uint64_t element)
{
    return ((uint64_t)array << 44 ^ element) + 1;
}

static size_t fill_slot(uint64_t key, size_t cap)
{
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return (size_t)key & (cap - 1);
}

static bool fill_grow(window_fill *f)
{
    size_t cap = f->cap ? 2 * f->cap : 4096;
    uint64_t *key = calloc(cap, sizeof *key);
    if (!key)
        return false;
    for (size_t i = 0; i < f->cap; i++)
        if (f->key[i]) {
            size_t j = fill_slot(f->key[i], cap);
            while (key[j])
                j = (j + 1) & (cap - 1);
            key[j] = f->key[i];
        }
    free(f->key);
    f->key = key;
    f->cap = cap;
    return true;
}

void window_fill_add(window_fill *f, uint32_t array, uint64_t element, uint64_t record_bytes)
{
    if (f->touched >= f->bytes)
        return;
    if (2 * (f->n + 1) > f->cap && !fill_grow(f)) {
        f->touched = f->bytes; /* no memory: the window ends at its length */
        return;
    }
    uint64_t k = fill_key(array, element);
    size_t j = fill_slot(k, f->cap);
    while (f->key[j] && f->key[j] != k)
        j = (j + 1) & (f->cap - 1);
    if (f->key[j])
        return;
    f->key[j] = k;
    f->n++;
    f->touched += record_bytes;
}

bool window_fill_done(const window_fill *f, uint64_t window, uint64_t n)
{
    uint64_t most = f->bytes ? emm_profile_fill_most(window) : window;
    return n >= most || (n >= window && f->touched >= f->bytes);
}

bool window_fill_filled(const window_fill *f)
{
    return f->bytes > 0 && f->touched >= f->bytes;
}

void window_fill_free(window_fill *f)
{
    free(f->key);
    *f = (window_fill){0};
}

/* EMM_* values through the configuration table (core/config.c): the first
 * byte picks the row, the rest is the value. A bad value must leave the
 * configuration as it was. */
#include "fuzz.h"
#include "emm/config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0)
        return 0;
    emm_config_key k = (emm_config_key)(data[0] % EMM_CONFIG_COUNT);
    char *s = fuzz_string(data + 1, size - 1);
    emm_config *c = malloc(sizeof *c), *before = malloc(sizeof *before);
    if (!c || !before)
        abort();
    emm_config_init(c);
    *before = *c;
    emm_error err;
    emm_status st = emm_config_set(c, k, s, NULL, 4242, &err);
    fuzz_check_error(st, &err);
    if (st != EMM_OK && memcmp(c, before, sizeof *c) != 0) {
        fprintf(stderr, "fuzz: a refused value changed the configuration\n");
        abort();
    }
    emm_config_free(c);
    free(c);
    free(before);
    free(s);
    return 0;
}

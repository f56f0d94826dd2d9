/* Strategy strings (core/strategy.c): a string that parses formats back to
 * a string that parses to the same strategy. */
#include "fuzz.h"
#include "emm/strategy.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s = fuzz_string(data, size);
    emm_strategy a, b;
    emm_error err;
    emm_status st = emm_strategy_parse(s, &a, &err);
    fuzz_check_error(st, &err);
    if (st == EMM_OK) {
        char text[128];
        emm_strategy_format(&a, text, sizeof text);
        if (emm_strategy_parse(text, &b, &err) != EMM_OK || memcmp(&a, &b, sizeof a) != 0) {
            fprintf(stderr, "fuzz: '%s' formats as '%s', which does not parse back\n", s, text);
            abort();
        }
    }
    free(s);
    return 0;
}

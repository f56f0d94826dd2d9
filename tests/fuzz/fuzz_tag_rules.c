/* EMM_TAG rules (core/tag_rules.c). */
#include "fuzz.h"
#include "emm/config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s = fuzz_string(data, size);
    emm_tag_rules rules;
    emm_error err;
    emm_status st = emm_tag_rules_parse(s, &rules, &err);
    fuzz_check_error(st, &err);
    if (st == EMM_OK)
        emm_tag_rules_free(&rules);
    free(s);
    return 0;
}

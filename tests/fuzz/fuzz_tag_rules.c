/* EMM_TAG rules (core/tag_rules.c). */
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "emm/config.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *s = fuzz_string(data, size);
    emm_tag_rules rules;
    emm_error err;
    emm_status st = emm_tag_rules_parse(s, &rules, &err);
    fuzz_check_error(st, &err);
    if (st == EMM_OK) {
        /* Each rule as EMM_TAG spells it reads back as the same rule (a
         * site=MODULE+0xHEX already in its spelling: lower-case hex, no
         * leading zeros), a half-edge rule's links included. */
        for (size_t i = 0; i < rules.n; i++) {
            char text[1024];
            emm_tag_rule again;
            emm_tag_rule_format(&rules.rule[i], text, sizeof text);
            if (strlen(text) + 1 < sizeof text &&
                (emm_tag_rule_parse(text, &again, &err) != EMM_OK ||
                 strcmp(again.site, rules.rule[i].site) != 0 || again.min != rules.rule[i].min ||
                 again.nth != rules.rule[i].nth || again.stride != rules.rule[i].stride ||
                 again.offset != rules.rule[i].offset || again.kind != rules.rule[i].kind ||
                 again.shape != rules.rule[i].shape || again.type != rules.rule[i].type ||
                 memcmp(again.link, rules.rule[i].link, sizeof again.link) != 0))
                abort();
        }
        emm_tag_rules_free(&rules);
    }
    free(s);
    return 0;
}

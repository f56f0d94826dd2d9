/* The JSON reader that emm plot reads reports with (core/json_read.c), and
 * the writer's strings read back: any bytes written as a JSON string must
 * parse and come back as valid UTF-8. */
#include "fuzz.h"
#include "json.h"
#include "json_read.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    jr_value *v = NULL;
    emm_error err;
    emm_status st = jr_parse((const char *)data, size, "fuzz.json", &v, &err);
    fuzz_check_error(st, &err);
    jr_free(v);

    /* The writer: the bytes (up to a NUL) as a string, read back. */
    char *s = fuzz_string(data, size);
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    if (!f)
        abort();
    json_write_string(f, s);
    fclose(f);
    st = jr_parse(text, len, "written", &v, &err);
    if (st != EMM_OK || !jr_is(v, JR_STRING)) {
        fprintf(stderr, "fuzz: the writer's string does not read back: %s\n", err.message);
        abort();
    }
    jr_free(v);
    free(text);
    free(s);
    return 0;
}

/* libemmhooks.so: the sanitizer-coverage callbacks as no-ops, so that a
 * program built with emm_sancov_executable (cmake/EmmSancov.cmake) links and
 * runs without emm; when libemmshim.so is preloaded, its definitions win.
 * It must stay a shared library: definitions linked into the executable
 * itself would come before the preload's.
 *
 * emm_sancov_hooks_present is the marker EMM_CAPTURE=auto looks for. */
#include <stdint.h>

#define HOOK __attribute__((visibility("default")))

HOOK extern const int emm_sancov_hooks_present;
const int emm_sancov_hooks_present = 1;

HOOK void __sanitizer_cov_load1(uint8_t *p);
HOOK void __sanitizer_cov_load2(uint16_t *p);
HOOK void __sanitizer_cov_load4(uint32_t *p);
HOOK void __sanitizer_cov_load8(uint64_t *p);
HOOK void __sanitizer_cov_load16(__int128 *p);
HOOK void __sanitizer_cov_store1(uint8_t *p);
HOOK void __sanitizer_cov_store2(uint16_t *p);
HOOK void __sanitizer_cov_store4(uint32_t *p);
HOOK void __sanitizer_cov_store8(uint64_t *p);
HOOK void __sanitizer_cov_store16(__int128 *p);
HOOK void __sanitizer_cov_trace_pc_guard(uint32_t *guard);
HOOK void __sanitizer_cov_trace_pc_guard_init(uint32_t *start, uint32_t *stop);

void __sanitizer_cov_load1(uint8_t *p) { (void)p; }
void __sanitizer_cov_load2(uint16_t *p) { (void)p; }
void __sanitizer_cov_load4(uint32_t *p) { (void)p; }
void __sanitizer_cov_load8(uint64_t *p) { (void)p; }
void __sanitizer_cov_load16(__int128 *p) { (void)p; }
void __sanitizer_cov_store1(uint8_t *p) { (void)p; }
void __sanitizer_cov_store2(uint16_t *p) { (void)p; }
void __sanitizer_cov_store4(uint32_t *p) { (void)p; }
void __sanitizer_cov_store8(uint64_t *p) { (void)p; }
void __sanitizer_cov_store16(__int128 *p) { (void)p; }
void __sanitizer_cov_trace_pc_guard(uint32_t *guard) { (void)guard; }

void __sanitizer_cov_trace_pc_guard_init(uint32_t *start, uint32_t *stop)
{
    (void)start;
    (void)stop;
}

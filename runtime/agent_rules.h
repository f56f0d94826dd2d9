/* Internal to the agent (runtime/agent.c): which allocation an EMM_TAG rule
 * selects, by a function on its call stack, by size or by rank; and the
 * call stacks list mode notes. The grammar, the names a frame answers to
 * and the messages are core's (core/tag_rules.c); what is here needs the
 * live call stack. */
#ifndef EMM_RUNTIME_AGENT_RULES_H
#define EMM_RUNTIME_AGENT_RULES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "emm/common.h"
#include "emm/config.h"

/* The most frames of a stack that are looked at. */
#define AGENT_MAX_FRAMES 32

typedef struct agent_rules agent_rules;

/* The matcher of the rules rs (borrowed: they must outlive it); the
 * unwinder is opened when a rule uses site= or `stacks` is set (list
 * mode). On failure err says why (libunwind is missing). */
emm_status agent_rules_new(const emm_tag_rules *rs, bool stacks, agent_rules **out,
                           emm_error *err);
void agent_rules_free(agent_rules *m);

/* The smallest block any rule can select (SIZE_MAX: no rules). */
size_t agent_rules_min(const agent_rules *m);
/* The rule (index, >= 0) that selects an allocation of `size` bytes made
 * now, from this call stack, or -1; counts nth= selectors; *site gets the
 * name of the frame a site= rule matched (else NULL). Thread-safe. */
int agent_rules_match(agent_rules *m, size_t size, const char **site);
/* A matcher of the rules rs that unwinds nothing, for agent_rules_replay:
 * list mode tries the rules it suggests on the run's recorded allocations. */
emm_status agent_rules_replayer(const emm_tag_rules *rs, agent_rules **out, emm_error *err);
/* agent_rules_match for an allocation of `size` bytes made from the
 * recorded stack name/ip (nframes frames, as agent_rules_stack gave them):
 * the same matching, selectors, call paths and nth= counts. */
int agent_rules_replay(agent_rules *m, size_t size, const char *const *name, const uintptr_t *ip,
                       int nframes, const char **site);
/* The blocks rule i's nth= has counted so far (0 for a rule without nth=):
 * with an nth= larger than any count, the rank each block would have. */
uint64_t agent_rules_counted(const agent_rules *m, size_t i);
/* The program's frames of this call stack (the agent's, the allocator's
 * and the standard library's left out), innermost first: each name
 * "name\0qualified\0" (or NULL) and return address; returns how many. */
int agent_rules_stack(agent_rules *m, const char **name, uintptr_t *ip);
/* Calls say(line) for each rule that selected no block, naming the sites
 * seen closest to it. */
void agent_rules_report(agent_rules *m, void (*say)(void *ctx, const char *line), void *ctx);

#endif

/* The DMA engine (thesis §3.2): the cost formula, two channels working in
 * parallel, a third transfer waiting for a channel, and the core stalling
 * only for what is left of a transfer. */
#include "check.h"
#include "dma.h"

int main(void)
{
    emm_machine *m;
    emm_error err;
    emm_dma d;
    uint64_t core, a, b, c;

    REQUIRE(emm_machine_new(&m, &err) == EMM_OK);
    emm_dma_init(&d, &m->p);

    /* One synchronous transfer: the core programs it (dma.program = 125),
     * the controller's latency (dma.latency = 141) and the transfer run on a
     * channel; 266 in all, as thesis §3.2. */
    a = emm_dma_start(&d, 0, 64, &core);
    CHECK(core == 125 && a == 125 + 141 + 16);
    CHECK(emm_dma_wait(core, a) == 141 + 16);
    emm_dma_reset(&d);

    /* Two long transfers overlap on the two channels; the core pays only
     * the programming. 4096 B: 2*512 + 208*3 = 1648 transfer cycles. */
    a = emm_dma_start(&d, 0, 4096, &core);
    CHECK(core == 125 && a == 125 + 141 + 1648);
    b = emm_dma_start(&d, core, 4096, &core);
    CHECK(core == 250 && b == 250 + 141 + 1648);
    /* A third must wait for the first channel to be free. */
    c = emm_dma_start(&d, core, 64, &core);
    CHECK(core == 375 && c == a + 141 + 16);
    /* The core waits only for what is left. */
    CHECK(emm_dma_wait(1000, c) == c - 1000);
    CHECK(emm_dma_wait(5000, c) == 0);
    CHECK(d.transfers == 3 && d.bytes == 4096 + 4096 + 64);

    /* One channel: everything is serial. */
    REQUIRE(emm_machine_set(m, "dma.channels=1", &err) == EMM_OK);
    emm_dma_init(&d, &m->p);
    a = emm_dma_start(&d, 0, 4096, &core);
    b = emm_dma_start(&d, core, 4096, &core);
    CHECK(a == 1914 && core == 250 && b == a + 141 + 1648);

    /* The old single key: dma.issue=X is all programming, no latency. */
    REQUIRE(emm_machine_set(m, "dma.issue=266", &err) == EMM_OK);
    emm_dma_init(&d, &m->p);
    a = emm_dma_start(&d, 0, 64, &core);
    CHECK(core == 266 && a == 282);
    REQUIRE(emm_machine_set(m, "dma.program=100", &err) == EMM_OK);
    REQUIRE(emm_machine_set(m, "dma.latency=166", &err) == EMM_OK);
    emm_dma_init(&d, &m->p);
    a = emm_dma_start(&d, 0, 64, &core);
    CHECK(core == 100 && a == 282);

    /* The formula at the acceptance sizes and chunk edges. */
    CHECK(emm_machine_dma_cycles(m, 1) == 266 + 2);
    CHECK(emm_machine_dma_cycles(m, 8) == 266 + 2);
    CHECK(emm_machine_dma_cycles(m, 9) == 266 + 4);
    CHECK(emm_machine_dma_cycles(m, 2048) == 266 + 512 + 208);
    CHECK(emm_machine_dma_cycles(m, 2049) == 266 + 514 + 416);
    emm_machine_free(m);
    return check_done();
}

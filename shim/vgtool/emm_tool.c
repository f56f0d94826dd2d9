/* emm's Valgrind tool (docs/design.md "The shim and the session", Capture backends:
 * valgrind): the whole run of an unmodified binary, every load and store that falls in an
 * array the shim tagged.
 *
 * Built out of tree against Debian's valgrind package (its tool headers and
 * static core libraries) as the static binary emm-amd64-linux, which
 * `valgrind --tool=emm` runs with VALGRIND_LIB pointing at the build's tool
 * directory (shim/vgtool/CMakeLists.txt lays it out). libemmshim.so stays
 * the tagging half inside the client; protocol.h is the channel.
 *
 * Instrumentation, per superblock:
 * - Every memory access (loads, stores, guarded ones, CAS, load-linked and
 *   store-conditional, dirty helpers' memory effects) gets an inline test
 *   against the intervals that cover the tagged ranges; only an access
 *   inside one calls the helper, which checks the exact ranges and appends
 *   a record with the instruction's address. Accesses outside every tagged
 *   array, nearly all of a program's, cost a subtraction and a comparison
 *   per interval: cheaper than Cachegrind, which calls a helper for every
 *   access.
 * - One interval first, covering every tagged range and what lies between
 *   them; a second interval costs every access of the program another test
 *   (on a smoothing loop, a tenth of the run). An access between the ranges
 *   calls the helper for nothing (a miss); once misses outnumber records
 *   and pass MISSES_FOR_TWO, the ranges are covered by WINDOWS intervals
 *   instead (closing the smallest gaps), and the code is translated again
 *   to test them, once in a run, at the next client request that drains
 *   or changes the ranges (more_windows).
 * - Each superblock of code that is not emm's adds one to `work`, the
 *   record's count of work since the previous one (sancov counts edges),
 *   in the program's threads only: the threads the session starts while
 *   the shim feeds it are emm's (thread_created).
 * - Code of emm's own libraries (libemm, libemmshim) is not instrumented:
 *   the session runs at Valgrind's base speed, and its own reads of the
 *   arrays are never records.
 * - A superblock of the program's own code (not the C library, the C++
 *   runtime, the loader or emm) starts with a test of `need_drain`: when the
 *   buffer is three-quarters full, the thread is sent to the shim's drain
 *   function as a signal handler would be (protocol.h), which feeds the
 *   records to the session and returns to the superblock's start. Records
 *   that arrive before that wait in the tool's own overflow buffer.
 * Valgrind runs one thread at a time, so the buffer holds every thread's
 * records in the order they ran: capture is exact with threads. */
#include "pub_tool_basics.h"
#include "pub_tool_clreq.h"
#include "pub_tool_debuginfo.h"
#include "pub_tool_libcassert.h"
#include "pub_tool_libcbase.h"
#include "pub_tool_libcprint.h"
#include "pub_tool_machine.h"
#include "pub_tool_mallocfree.h"
#include "pub_tool_options.h"
#include "pub_tool_tooliface.h"
#include "pub_tool_transtab.h"
#include "libvex_guest_amd64.h"

#include "protocol.h"

#define MAX_RANGES 64
/* Intervals tested inline per access at most (one until misses call for
 * more: more_windows); the tagged ranges are merged into that many
 * (closing the smallest gaps), and the helper tests them exactly. A mesh
 * program tags two or three arrays. */
#define WINDOWS 2
/* Misses (helper calls outside every tagged range) before a second
 * interval is worth its test on every access, when they also outnumber
 * the records. */
#define MISSES_FOR_TWO (1ULL << 20)
/* Bytes below the stack pointer left alone when a thread is sent to drain:
 * the x86-64 red zone, and the return address. */
#define RED_ZONE 128

/* The tagged ranges, sorted by start. */
static ULong range_lo[MAX_RANGES], range_hi[MAX_RANGES];
static UInt nranges;
/* Read by the instrumented code. */
static ULong win_lo[WINDOWS], win_len[WINDOWS];
/* The intervals the instrumentation tests (1, then WINDOWS once misses
 * call for it), and whether the helper asked for the switch. */
static UInt nwin = 1;
static Bool want_more_windows;
static ULong need_drain;
static ULong work;
/* `work` when the shim began feeding the session (BUSY). */
static ULong work_before_busy;
static Bool busy;
/* What a superblock adds to `work`: 1 in the program's threads, 0 in
 * emm's, the threads started while the shim fed the session (the session's
 * helper threads, which run rounds of its simulation): they wake and wait
 * in the C library on their own schedule, after BUSY(0) as often as
 * before, and their superblocks are not the program's work. */
static ULong work_step = 1;
/* Thread ids Valgrind hands out (its --max-threads, 500 by default); a
 * thread beyond counts as the program's. */
#define MAX_THREAD_IDS 4096
static Bool emm_thread[MAX_THREAD_IDS];

/* The channel (client memory), the records in it, and those that did not
 * fit yet. */
static struct emm_vg_channel *chan;
static struct emm_vg_record *buf;
static ULong cap, n, high_water;
static struct emm_vg_record *over;
static ULong over_head, over_n, over_cap;
static Addr drain_entry;

/* --emm-stats=yes: what the capture did, at exit. */
static Bool show_stats;
static ULong stat_records, stat_drains, stat_diverted, stat_over_peak, stat_misses;

/* ---- the records ------------------------------------------------------- */

static struct emm_vg_record *slot(void)
{
    if (n < cap)
        return &buf[n++];
    if (over_n == over_cap) {
        over_cap = over_cap ? 2 * over_cap : 65536;
        over = VG_(realloc)("emm.overflow", over, over_cap * sizeof *over);
    }
    if (over_n + 1 - over_head > stat_over_peak)
        stat_over_peak = over_n + 1 - over_head;
    return &over[over_n++];
}

static VG_REGPARM(3) void hit(Addr a, UWord bytes_write, Addr pc)
{
    for (UInt i = 0; i < nranges; i++) {
        if (a - range_lo[i] < range_hi[i] - range_lo[i]) {
            if (!buf)
                return;
            struct emm_vg_record *r = slot();
            r->addr = a;
            r->bytes_write = (UInt)bytes_write;
            r->work = work > 0xffffffffULL ? 0xffffffffu : (UInt)work;
            r->pc = pc;
            work = 0;
            stat_records++;
            if (n >= high_water && drain_entry)
                need_drain = 1;
            return;
        }
    }
    stat_misses++;
    if (nwin < WINDOWS && stat_misses >= MISSES_FOR_TWO && stat_misses > stat_records)
        want_more_windows = True;
}

/* The buffer was consumed: the overflow's oldest records move into it. */
static ULong refill(void)
{
    n = 0;
    while (n < cap && over_head < over_n)
        buf[n++] = over[over_head++];
    if (over_head == over_n)
        over_head = over_n = 0;
    return n;
}

/* Merges the sorted ranges into nwin intervals by closing the smallest
 * gaps between neighbours. */
static void set_windows(void)
{
    ULong lo[MAX_RANGES], hi[MAX_RANGES];
    UInt k = nranges;
    for (UInt i = 0; i < k; i++) {
        lo[i] = range_lo[i];
        hi[i] = range_hi[i];
    }
    while (k > nwin) {
        UInt best = 0;
        for (UInt i = 1; i + 1 < k; i++)
            if (lo[i + 1] - hi[i] < lo[best + 1] - hi[best])
                best = i;
        if (hi[best + 1] > hi[best])
            hi[best] = hi[best + 1];
        for (UInt i = best + 1; i + 1 < k; i++) {
            lo[i] = lo[i + 1];
            hi[i] = hi[i + 1];
        }
        k--;
    }
    for (UInt w = 0; w < WINDOWS; w++) {
        win_lo[w] = w < k ? lo[w] : 0;
        win_len[w] = w < k ? hi[w] - lo[w] : 0;
    }
}

static void set_ranges(const ULong *lo, const ULong *hi, UWord count)
{
    nranges = 0;
    for (UWord i = 0; i < count && nranges < MAX_RANGES; i++) {
        if (hi[i] <= lo[i])
            continue;
        UInt j = nranges++;
        while (j > 0 && range_lo[j - 1] > lo[i]) {
            range_lo[j] = range_lo[j - 1];
            range_hi[j] = range_hi[j - 1];
            j--;
        }
        range_lo[j] = lo[i];
        range_hi[j] = hi[i];
    }
    set_windows();
}

/* The switch to WINDOWS intervals the helper asked for, at a client
 * request (outside translated code, which it discards): at the next drain
 * or change of the ranges. Not a drain of its own: the session reads the
 * program's memory at a drain, and the drains stay where the buffer puts
 * them, switch or not. */
static void more_windows(void)
{
    if (!want_more_windows || nwin == WINDOWS)
        return;
    want_more_windows = False;
    nwin = WINDOWS;
    set_windows();
    VG_(discard_translations_safely)((Addr)0x1000, ~(SizeT)0x1000, "emm.windows");
}

/* ---- the code's classes ------------------------------------------------- */

enum code_class {
    CODE_PROGRAM, /* the program's own: instrumented, counted, a place to drain */
    CODE_SYSTEM,  /* the C library, the C++ runtime, the loader: instrumented, counted */
    CODE_EMM      /* emm's own libraries and Valgrind's preload: left alone */
};

static Bool has_prefix(const HChar *s, const HChar *p)
{
    return VG_(strncmp)(s, p, VG_(strlen)(p)) == 0;
}

/* The class of the code of the object at `path`. */
static enum code_class classify_object(const HChar *path)
{
    static const HChar *const emm[] = {"libemm.so", "libemmshim.so", "vgpreload_"};
    static const HChar *const sys[] = {"libc.so",      "ld-linux",   "libpthread", "libdl.so",
                                       "librt.so",     "libstdc++",  "libgcc_s",   "libm.so",
                                       "libunwind",    "libzstd",    "libdw",      "libelf"};
    const HChar *base = VG_(strrchr)(path, '/');
    base = base ? base + 1 : path;
    for (UInt i = 0; i < sizeof emm / sizeof *emm; i++)
        if (has_prefix(base, emm[i]))
            return CODE_EMM;
    for (UInt i = 0; i < sizeof sys / sizeof *sys; i++)
        if (has_prefix(base, sys[i]))
            return CODE_SYSTEM;
    return CODE_PROGRAM;
}

static enum code_class classify(Addr a)
{
    const HChar *name;
    if (!VG_(get_objname)(VG_(current_DiEpoch)(), a, &name))
        return CODE_SYSTEM; /* no object known (the vDSO, generated code): not a place to drain */
    return classify_object(name);
}

/* Translates the program's code again: only there does the instrumentation
 * test need_drain (instrument()), which code translated before the drain
 * function was known lacks. The C library's and the loader's translations,
 * which the shim's start-up used and goes on using, stay: translating them
 * again cost the start of every run some 10 ms more. */
static void retranslate_program(void)
{
    for (const DebugInfo *di = VG_(next_DebugInfo)(NULL); di; di = VG_(next_DebugInfo)(di)) {
        Addr lo = VG_(DebugInfo_get_text_avma)(di);
        SizeT len = VG_(DebugInfo_get_text_size)(di);
        const HChar *path = VG_(DebugInfo_get_filename)(di);
        if (len && path && classify_object(path) == CODE_PROGRAM)
            VG_(discard_translations_safely)(lo, len, "emm.channel");
    }
}

/* ---- the client's requests --------------------------------------------- */

static Bool client_request(ThreadId tid, UWord *arg, UWord *ret)
{
    (void)tid;
    if (!VG_IS_TOOL_USERREQ('E', 'M', arg[0]))
        return False;
    *ret = 0;
    switch (arg[0]) {
    case EMM_VG_HELLO:
        *ret = EMM_VG_VERSION;
        break;
    case EMM_VG_CHANNEL:
        chan = (struct emm_vg_channel *)arg[1];
        buf = chan->rec;
        cap = chan->cap;
        high_water = cap - cap / 4;
        drain_entry = (Addr)chan->drain;
        n = 0;
        retranslate_program();
        *ret = 1;
        break;
    case EMM_VG_RANGES:
        more_windows();
        set_ranges((const ULong *)arg[1], (const ULong *)arg[2], arg[3]);
        break;
    case EMM_VG_TAKE:
        more_windows();
        stat_diverted += need_drain != 0;
        stat_drains++;
        need_drain = 0;
        *ret = n;
        break;
    case EMM_VG_RELEASE:
        *ret = refill();
        break;
    case EMM_VG_LATER:
        need_drain = 0;
        break;
    case EMM_VG_BUSY:
        busy = arg[1] != 0;
        if (busy)
            work_before_busy = work;
        else
            work = work_before_busy;
        break;
    case EMM_VG_STOP:
        set_ranges(NULL, NULL, 0);
        buf = NULL;
        drain_entry = 0;
        need_drain = 0;
        n = over_head = over_n = 0;
        break;
    default:
        return False;
    }
    return True;
}

/* ---- instrumentation ---------------------------------------------------- */

static IRExpr *u64(ULong v)
{
    return IRExpr_Const(IRConst_U64(v));
}

/* t = e, and the temporary. */
static IRTemp assign(IRSB *sb, IRType ty, IRExpr *e)
{
    IRTemp t = newIRTemp(sb->tyenv, ty);
    addStmtToIRSB(sb, IRStmt_WrTmp(t, e));
    return t;
}

static IRTemp load64(IRSB *sb, const void *host)
{
    return assign(sb, Ity_I64, IRExpr_Load(Iend_LE, Ity_I64, u64((ULong)(HWord)host)));
}

/* The windows, loaded once per superblock at its first access: a client
 * request (the only way they change) ends a superblock. */
struct sb_state {
    Bool loaded;
    IRTemp lo[WINDOWS], len[WINDOWS];
};

static void record_access(IRSB *sb, struct sb_state *s, IRExpr *addr, Int bytes, Bool write,
                          Addr pc, IRExpr *guard)
{
    if (bytes <= 0)
        return;
    if (!s->loaded) {
        for (UInt w = 0; w < nwin; w++) {
            s->lo[w] = load64(sb, &win_lo[w]);
            s->len[w] = load64(sb, &win_len[w]);
        }
        s->loaded = True;
    }
    if (addr->tag != Iex_RdTmp && addr->tag != Iex_Const)
        addr = IRExpr_RdTmp(assign(sb, Ity_I64, addr));
    IRTemp in = IRTemp_INVALID;
    for (UInt w = 0; w < nwin; w++) {
        IRTemp d = assign(sb, Ity_I64, IRExpr_Binop(Iop_Sub64, addr, IRExpr_RdTmp(s->lo[w])));
        IRTemp c = assign(sb, Ity_I1,
                          IRExpr_Binop(Iop_CmpLT64U, IRExpr_RdTmp(d), IRExpr_RdTmp(s->len[w])));
        in = in == IRTemp_INVALID
                 ? c
                 : assign(sb, Ity_I1, IRExpr_Binop(Iop_Or1, IRExpr_RdTmp(in), IRExpr_RdTmp(c)));
    }
    if (guard)
        in = assign(sb, Ity_I1, IRExpr_Binop(Iop_And1, IRExpr_RdTmp(in), guard));
    /* A record's pc is an address one byte into the access's instruction,
     * as the sancov hooks' return address is one past their call: the
     * source lines are looked up one byte back (runtime/srcline.c), which
     * from the instruction's own address would land in the instruction
     * before it, on another line or in another inlined function. */
    IRDirty *di = unsafeIRDirty_0_N(
        3, "emm_hit", VG_(fnptr_to_fnentry)(hit),
        mkIRExprVec_3(addr, u64((ULong)bytes | (write ? EMM_VG_WRITE : 0u)), u64(pc + 1)));
    di->guard = IRExpr_RdTmp(in);
    addStmtToIRSB(sb, IRStmt_Dirty(di));
}

/* work += work_step */
static void count_work(IRSB *sb)
{
    IRTemp w = load64(sb, &work), step = load64(sb, &work_step);
    IRTemp w1 = assign(sb, Ity_I64, IRExpr_Binop(Iop_Add64, IRExpr_RdTmp(w), IRExpr_RdTmp(step)));
    addStmtToIRSB(sb, IRStmt_Store(Iend_LE, u64((ULong)(HWord)&work), IRExpr_RdTmp(w1)));
}

/* When need_drain is set: push `pc` below the red zone and jump to the
 * drain function, which returns here with `ret $RED_ZONE`. */
static void maybe_drain(IRSB *sb, Addr pc)
{
    Int rsp = (Int)__builtin_offsetof(VexGuestAMD64State, guest_RSP);
    Int rip = (Int)__builtin_offsetof(VexGuestAMD64State, guest_RIP);
    IRTemp flag = load64(sb, &need_drain);
    IRTemp go = assign(sb, Ity_I1, IRExpr_Binop(Iop_CmpNE64, IRExpr_RdTmp(flag), u64(0)));
    IRTemp sp = assign(sb, Ity_I64, IRExpr_Get(rsp, Ity_I64));
    IRTemp below = assign(sb, Ity_I64,
                          IRExpr_Binop(Iop_Sub64, IRExpr_RdTmp(sp), u64(RED_ZONE + 8)));
    addStmtToIRSB(sb, IRStmt_StoreG(Iend_LE, IRExpr_RdTmp(below), u64(pc), IRExpr_RdTmp(go)));
    IRTemp nsp = assign(sb, Ity_I64,
                        IRExpr_ITE(IRExpr_RdTmp(go), IRExpr_RdTmp(below), IRExpr_RdTmp(sp)));
    addStmtToIRSB(sb, IRStmt_Put(rsp, IRExpr_RdTmp(nsp)));
    addStmtToIRSB(sb, IRStmt_Exit(IRExpr_RdTmp(go), Ijk_Boring, IRConst_U64(drain_entry), rip));
}

static Int loadg_bytes(IRLoadGOp cvt)
{
    switch (cvt) {
    case ILGop_IdentV128: return 16;
    case ILGop_Ident64: return 8;
    case ILGop_Ident32: return 4;
    case ILGop_16Uto32:
    case ILGop_16Sto32: return 2;
    case ILGop_8Uto32:
    case ILGop_8Sto32: return 1;
    default: return 0;
    }
}

static IRSB *instrument(VgCallbackClosure *closure, IRSB *in, const VexGuestLayout *layout,
                        const VexGuestExtents *vge, const VexArchInfo *archinfo_host,
                        IRType gWordTy, IRType hWordTy)
{
    (void)layout; (void)vge; (void)archinfo_host;
    if (gWordTy != Ity_I64 || hWordTy != Ity_I64)
        VG_(tool_panic)("emm: 64-bit guests only");
    enum code_class cls = classify(closure->readdr);
    if (cls == CODE_EMM)
        return in;
    IRSB *out = deepCopyIRSBExceptStmts(in);
    IRTypeEnv *env = in->tyenv;
    struct sb_state s = {False, {0}, {0}};
    Bool first = True;
    Addr pc = 0;
    Int i = 0;
    for (; i < in->stmts_used && in->stmts[i]->tag != Ist_IMark; i++)
        addStmtToIRSB(out, in->stmts[i]);
    for (; i < in->stmts_used; i++) {
        IRStmt *st = in->stmts[i];
        if (!st || st->tag == Ist_NoOp)
            continue;
        switch (st->tag) {
        case Ist_IMark:
            pc = (Addr)st->Ist.IMark.addr;
            addStmtToIRSB(out, st);
            if (first) {
                first = False;
                count_work(out);
                /* Only where the thread may be interrupted as by a signal:
                 * the program's code, reached without a redirection. */
                if (cls == CODE_PROGRAM && drain_entry && closure->nraddr == closure->readdr)
                    maybe_drain(out, pc);
            }
            continue;
        case Ist_WrTmp:
            if (st->Ist.WrTmp.data->tag == Iex_Load) {
                IRExpr *e = st->Ist.WrTmp.data;
                record_access(out, &s, e->Iex.Load.addr, sizeofIRType(e->Iex.Load.ty), False, pc,
                              NULL);
            }
            break;
        case Ist_Store:
            record_access(out, &s, st->Ist.Store.addr,
                          sizeofIRType(typeOfIRExpr(env, st->Ist.Store.data)), True, pc, NULL);
            break;
        case Ist_LoadG: {
            IRLoadG *lg = st->Ist.LoadG.details;
            record_access(out, &s, lg->addr, loadg_bytes(lg->cvt), False, pc, lg->guard);
            break;
        }
        case Ist_StoreG: {
            IRStoreG *sg = st->Ist.StoreG.details;
            record_access(out, &s, sg->addr, sizeofIRType(typeOfIRExpr(env, sg->data)), True, pc,
                          sg->guard);
            break;
        }
        case Ist_CAS: {
            IRCAS *cas = st->Ist.CAS.details;
            Int b = sizeofIRType(typeOfIRExpr(env, cas->dataLo)) * (cas->dataHi ? 2 : 1);
            record_access(out, &s, cas->addr, b, True, pc, NULL);
            break;
        }
        case Ist_LLSC:
            if (st->Ist.LLSC.storedata)
                record_access(out, &s, st->Ist.LLSC.addr,
                              sizeofIRType(typeOfIRExpr(env, st->Ist.LLSC.storedata)), True, pc,
                              NULL);
            else
                record_access(out, &s, st->Ist.LLSC.addr,
                              sizeofIRType(typeOfIRTemp(env, st->Ist.LLSC.result)), False, pc,
                              NULL);
            break;
        case Ist_Dirty: {
            IRDirty *d = st->Ist.Dirty.details;
            if (d->mFx != Ifx_None && d->mAddr)
                record_access(out, &s, d->mAddr, d->mSize, d->mFx != Ifx_Read, pc, NULL);
            break;
        }
        default:
            break;
        }
        addStmtToIRSB(out, st);
    }
    return out;
}

/* ---- start and end ------------------------------------------------------- */

static void post_clo_init(void)
{
}

/* A thread started while the shim feeds the session, or by one of emm's
 * threads, is emm's. */
static void thread_created(ThreadId parent, ThreadId child)
{
    if (child < MAX_THREAD_IDS)
        emm_thread[child] = busy || (parent < MAX_THREAD_IDS && emm_thread[parent]);
}

static void thread_runs(ThreadId tid, ULong blocks_done)
{
    (void)blocks_done;
    work_step = tid < MAX_THREAD_IDS && emm_thread[tid] ? 0 : 1;
}

static Bool command_line_option(const HChar *arg)
{
    if VG_BOOL_CLO(arg, "--emm-stats", show_stats) {
    } else {
        return False;
    }
    return True;
}

static void usage(void)
{
    VG_(printf)("    --emm-stats=no|yes        what the capture did, at exit [no]\n");
}

static void fini(Int exitcode)
{
    (void)exitcode;
    if (show_stats)
        VG_(umsg)("emm tool: %llu records, %llu drains (%llu with the buffer full), "
                  "overflow peak %llu records, %llu misses, %u interval%s tested\n",
                  stat_records, stat_drains, stat_diverted, stat_over_peak, stat_misses, nwin,
                  nwin == 1 ? "" : "s");
}

static void pre_clo_init(void)
{
    VG_(details_name)("emm");
    VG_(details_version)(NULL);
    VG_(details_description)("the access capture of emm run --capture valgrind");
    VG_(details_copyright_author)("emm's authors; Valgrind's core by Julian Seward et al.");
    VG_(details_bug_reports_to)("emm's issue tracker");
    VG_(details_avg_translation_sizeB)(275);
    VG_(basic_tool_funcs)(post_clo_init, instrument, fini);
    VG_(needs_client_requests)(client_request);
    VG_(needs_command_line_options)(command_line_option, usage, usage);
    VG_(track_pre_thread_ll_create)(thread_created);
    VG_(track_start_client_code)(thread_runs);
}

VG_DETERMINE_INTERFACE_VERSION(pre_clo_init)

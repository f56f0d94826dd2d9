/* region_growing — the region-growing workload of thesis §4.3.2.
 *
 * By default, the thesis' own Program 4.2, as written: a breadth-first
 * conquest from triangle 0 ("the traversals all grow ring by ring", §2.1.1).
 * Its three vertices start the active list. The list's *front* is the focus;
 * it leaves the list, and each of its incident vertices, in rotation order,
 * is either free — conquered, appended at the list's *back*, its code
 * "A<valence>" output — or, when it is still in the active list with free
 * triangles around it, a split: the pseudo-code puts it in a second list
 * pushed on a stack for later treatment (each vertex at most once here, so
 * the stack stays finite). A breadth-first front meets itself at nearly
 * every step this way, so most of those lists enclose nothing by the time
 * they are popped: a list whose vertex is full (no free triangle) is
 * dropped unread, as Touma and Gotsman drop a list of two vertices, and
 * only a list around territory still free (behind a hole, say) is grown.
 * When the list is empty the next list is popped; when the stack is empty
 * the next component starts at its lowest free triangle. A vertex's valence is its triangle count, which a first pass
 * over the triangles counts; "full" is a count of free triangles down to 0.
 * Output: "codes: N\nsplits: S\nchecksum: 0x...\n", checksum the FNV-1a of
 * the code sequence (--print-codes). Invariants: every vertex with a
 * triangle conquered exactly once, every triangle conquered, the valences
 * adding up to 3 x triangles.
 *
 * With --conquest, the valence-driven connectivity encoding of Touma and
 * Gotsman [16] that Program 4.2 abbreviates (the triangle conquest of
 * §2.1.1, Fig. 2.3; Alliez and Desbrun refine it), described below: a
 * pivot keeps conquering its one-ring until it is full, so the front
 * advances in a spiral rather than ring by ring.
 *
 * The conquered region grows from a seed triangle. Its border is kept as
 * cyclic *active lists* of vertices; consecutive vertices u -> w in a list
 * are joined by a *gate* edge with a conquered triangle on one side and a
 * free one on the other. The front of the current list is the *pivot* p; with
 * n its successor, the free triangle across the gate (p, n) is conquered and
 * its third vertex x decides what happens:
 *
 *   x free                  x is conquered and inserted between p and n;
 *                           code "A<valence>" ("D<valence>" for a dummy
 *                           vertex, below);
 *   x is p's predecessor a  the triangle closes p's fan: p is full and leaves
 *                           the list; a becomes the pivot;
 *   x follows n             n is full and leaves the list;
 *   x elsewhere in the list the list splits in two at x; the part from n to
 *                           x is pushed on a stack for later and the conquest
 *                           goes on around p; code "S<offset>", the offset
 *                           being x's distance from p along the list;
 *   x in a stacked list     (a handle: only on meshes of genus > 0) the two
 *                           lists merge; code "M<depth>,<offset>", the depth
 *                           of the list in the stack and x's distance from
 *                           its front.
 *
 * Two refinements keep splits rare (a few per cent of the vertices on an
 * irregular mesh, none on a regular grid): a dummy vertex is never the pivot
 * (the vertex before it is), and a predecessor of the pivot whose last free
 * triangle closes its fan is closed first (close_ear, after Alliez and
 * Desbrun's choice of the pivot with the fewest free edges).
 *
 * A list of two vertices encloses nothing and is dropped; the next list is
 * popped from the stack. Valences are those of the mesh closed as Touma and
 * Gotsman close it: every boundary loop gets a *dummy vertex* joined to each
 * of its vertices by a dummy triangle per boundary edge (these live in this
 * program's own arrays; the mesh records are never extended). When the stack
 * is empty the next component starts at the lowest-numbered free triangle
 * ("A" codes for its three vertices).
 *
 * At the end the program checks its invariants and exits 1 naming the first
 * one violated: every vertex that has a triangle (and every dummy vertex) was
 * conquered exactly once, every triangle (real and dummy) was conquered, the
 * valences in the codes add up to 3 * triangles (each triangle has three
 * corners), no list node is left, and the merges equal the total genus the
 * Euler characteristic gives.
 *
 * Output: "codes: N\nsplits: S\nmerges: M\nchecksum: 0x...\n", where the
 * checksum is FNV-1a 64 of the code sequence as `--print-codes` prints it,
 * one code per line, each line ending in '\n'.
 *
 * One-rings are walked through `neighbors` (vertex_fan in workload.c); the
 * 12 vfConnec slots are only used to start the walk. */
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "workload.h"

#define PROG "region_growing"

static void usage(FILE *out)
{
    fputs("usage: " PROG " [--conquest] [--print-codes] [--times] [MESH]\n"
          "\n"
          "Grows a region over a triangle mesh as the thesis' Program 4.2 does (section\n"
          "4.3.2): a breadth-first conquest of the vertices from triangle 0, ring by\n"
          "ring, outputting each conquered vertex's valence; checks its invariants and\n"
          "prints the code count, the splits and a checksum of the code sequence.\n"
          "MESH is an OFF, OBJ, PLY or STL file; without it the default mesh (20,000\n"
          "clustered faces, seed 1) is generated in memory.\n"
          "\n"
          "  --conquest       the valence-driven encoding of Touma and Gotsman instead\n"
          "                   (pivots conquer their one-ring until full; also prints\n"
          "                   merges)\n"
          "  --print-codes    also print the code sequence, one code per line, first\n"
          "  --times          print load and traversal seconds on stderr\n",
          out);
}


/* The conquest's state. Triangle ids >= nt are dummy triangles and vertex
 * ids >= nv dummy vertices, both in this program's arrays. */
struct rg {
    const struct Mesh *m;
    int32_t nv, nt;       /* real vertices and triangles */
    int32_t NV, NT;       /* with the dummies */
    int32_t *bnd;         /* 3 per real triangle: the dummy across a boundary edge, -1 */
    int32_t *dv, *dn;     /* dummy triangles: 3 vertices, 3 neighbours each */
    int32_t *loop_len;    /* per dummy vertex: its valence */
    unsigned char *tconq; /* per triangle */
    uint32_t *vconq;      /* per vertex: times conquered */
    /* List nodes: vertex, cyclic links, list, gate triangle (the conquered
     * triangle on the edge to the next node), and the vertex's other nodes. */
    int32_t *nv_, *nnext, *nprev, *nlist, *ngate, *nvnext;
    int32_t *vhead;       /* per vertex: its first node, -1 */
    int32_t free_node, nodes_cap, live_nodes;
    int32_t *lfront, *llen;
    unsigned char *lalive;
    int32_t nlists, lists_cap;
    int32_t *stack;
    int32_t depth, stack_cap;
    /* Output. */
    uint64_t codes, splits, merges, valence_sum, checksum;
    bool print;
};

static void *xmalloc(size_t n)
{
    void *p = malloc(n ? n : 1);
    if (!p) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(1);
    }
    return p;
}

static void *xrealloc(void *p, size_t n)
{
    p = realloc(p, n);
    if (!p) {
        fprintf(stderr, PROG ": out of memory\n");
        exit(1);
    }
    return p;
}

static _Noreturn void violated(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

static _Noreturn void violated(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fprintf(stderr, PROG ": invariant violated: ");
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    exit(1);
}

static int32_t xvert(const struct rg *g, int32_t t, int i)
{
    return t < g->nt ? g->m->triangles[t].vertexIndices[i] : g->dv[3 * (t - g->nt) + i];
}

static int32_t xneigh(const struct rg *g, int32_t t, int i)
{
    if (t >= g->nt)
        return g->dn[3 * (t - g->nt) + i];
    int32_t n = g->m->triangles[t].neighbors[i];
    return n >= 0 ? n : g->bnd[3 * t + i];
}

/* The triangle across edge (a, b) of triangle t in the closed mesh. */
static int32_t xacross(const struct rg *g, int32_t t, int32_t a, int32_t b)
{
    for (int i = 0; i < 3; i++) {
        int32_t x = xvert(g, t, i), y = xvert(g, t, (i + 1) % 3);
        if ((x == a && y == b) || (x == b && y == a))
            return xneigh(g, t, i);
    }
    violated("triangle %" PRId32 " has no edge (%" PRId32 ", %" PRId32 ")", t, a, b);
}

/* Closes every boundary loop with a dummy vertex and one dummy triangle per
 * boundary edge (b, a, dummy), whose edge 0 faces the real triangle and
 * edges 1 and 2 the dummy triangles of the neighbouring boundary edges. */
static void close_boundaries(struct rg *g)
{
    const struct Mesh *m = g->m;
    int32_t nt = g->nt, nd = 0;
    g->bnd = xmalloc(3 * (size_t)nt * sizeof *g->bnd);
    for (int32_t t = 0; t < nt; t++)
        for (int i = 0; i < 3; i++)
            g->bnd[3 * t + i] = m->triangles[t].neighbors[i] < 0 ? nt + nd++ : -1;
    g->dv = xmalloc(3 * (size_t)nd * sizeof *g->dv);
    g->dn = xmalloc(3 * (size_t)nd * sizeof *g->dn);
    int32_t *vb = xmalloc(2 * (size_t)g->nv * sizeof *vb); /* a vertex's two boundary edges */
    for (int32_t i = 0; i < 2 * g->nv; i++)
        vb[i] = -1;
    for (int32_t t = 0; t < nt; t++) {
        for (int i = 0; i < 3; i++) {
            int32_t d = g->bnd[3 * t + i];
            if (d < 0)
                continue;
            int32_t k = d - nt;
            int32_t a = m->triangles[t].vertexIndices[i];
            int32_t b = m->triangles[t].vertexIndices[(i + 1) % 3];
            g->dv[3 * k] = b;
            g->dv[3 * k + 1] = a;
            g->dv[3 * k + 2] = -1;
            g->dn[3 * k] = t;
            int32_t ends[2] = {a, b};
            for (int e = 0; e < 2; e++) {
                int32_t *slot = &vb[2 * ends[e]];
                if (slot[0] < 0)
                    slot[0] = k;
                else if (slot[1] < 0)
                    slot[1] = k;
                else
                    violated("vertex %" PRId32 " is on more than two boundary edges", ends[e]);
            }
        }
    }
    for (int32_t k = 0; k < nd; k++) {
        for (int e = 1; e <= 2; e++) {
            int32_t w = g->dv[3 * k + (e == 1 ? 1 : 0)];
            int32_t other = vb[2 * w] == k ? vb[2 * w + 1] : vb[2 * w];
            if (other < 0)
                violated("boundary vertex %" PRId32 " has one boundary edge", w);
            g->dn[3 * k + e] = nt + other;
        }
    }
    /* Label the loops by walking each from boundary edge to boundary edge. */
    int32_t loops = 0;
    g->loop_len = NULL;
    for (int32_t k = 0; k < nd; k++) {
        if (g->dv[3 * k + 2] >= 0)
            continue;
        int32_t dummy = g->nv + loops++;
        g->loop_len = xrealloc(g->loop_len, (size_t)loops * sizeof *g->loop_len);
        int32_t len = 0, j = k, w = g->dv[3 * k + 1];
        do {
            g->dv[3 * j + 2] = dummy;
            len++;
            int32_t next = vb[2 * w] == j ? vb[2 * w + 1] : vb[2 * w];
            w = g->dv[3 * next] == w ? g->dv[3 * next + 1] : g->dv[3 * next];
            j = next;
        } while (j != k && len <= nd);
        g->loop_len[loops - 1] = len;
    }
    free(vb);
    g->NV = g->nv + loops;
    g->NT = nt + nd;
}

/* The valence of vertex v in the closed mesh: its triangles, plus the two
 * dummy triangles at a boundary vertex. */
static int32_t valence(const struct rg *g, int32_t v)
{
    if (v >= g->nv)
        return g->loop_len[v - g->nv];
    bool open;
    size_t n = vertex_fan(g->m, v, NULL, 0, &open);
    return (int32_t)n + (open ? 2 : 0);
}

static void emit(struct rg *g, const char *code)
{
    g->codes++;
    g->checksum = fnv1a64_line(g->checksum, code);
    if (g->print)
        puts(code);
}

static void conquer_vertex(struct rg *g, int32_t v)
{
    char code[32];
    int32_t val = valence(g, v);
    g->vconq[v]++;
    g->valence_sum += (uint64_t)val;
    snprintf(code, sizeof code, "%c%" PRId32, v >= g->nv ? 'D' : 'A', val);
    emit(g, code);
}

static int32_t new_node(struct rg *g, int32_t v, int32_t list)
{
    /* Freed nodes first; when none is left every index handed out is live,
     * so the next fresh one is live_nodes. */
    int32_t k = g->free_node;
    if (k >= 0) {
        g->free_node = g->nnext[k];
    } else {
        if (g->live_nodes == g->nodes_cap) {
            size_t cap = g->nodes_cap ? 2 * (size_t)g->nodes_cap : 1024;
            int32_t **arrays[] = {&g->nv_, &g->nnext, &g->nprev, &g->nlist, &g->ngate, &g->nvnext};
            for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
                *arrays[i] = xrealloc(*arrays[i], cap * sizeof **arrays[i]);
            g->nodes_cap = (int32_t)cap;
        }
        k = g->live_nodes;
    }
    g->live_nodes++;
    g->nv_[k] = v;
    g->nlist[k] = list;
    g->nvnext[k] = g->vhead[v];
    g->vhead[v] = k;
    return k;
}

static void free_node(struct rg *g, int32_t k)
{
    int32_t *link = &g->vhead[g->nv_[k]];
    while (*link != k)
        link = &g->nvnext[*link];
    *link = g->nvnext[k];
    g->nnext[k] = g->free_node;
    g->free_node = k;
    g->live_nodes--;
}

static int32_t new_list(struct rg *g)
{
    if (g->nlists == g->lists_cap) {
        size_t cap = g->lists_cap ? 2 * (size_t)g->lists_cap : 64;
        g->lfront = xrealloc(g->lfront, cap * sizeof *g->lfront);
        g->llen = xrealloc(g->llen, cap * sizeof *g->llen);
        g->lalive = xrealloc(g->lalive, cap * sizeof *g->lalive);
        g->stack = xrealloc(g->stack, cap * sizeof *g->stack);
        g->lists_cap = (int32_t)cap;
    }
    g->lalive[g->nlists] = 1;
    g->llen[g->nlists] = 0;
    return g->nlists++;
}

static void push(struct rg *g, int32_t list)
{
    g->stack[g->depth++] = list; /* stack_cap == lists_cap: a list is pushed once */
}

/* Links node k between prev and next. */
static void link_between(struct rg *g, int32_t k, int32_t prev, int32_t next)
{
    g->nnext[prev] = k;
    g->nprev[k] = prev;
    g->nnext[k] = next;
    g->nprev[next] = k;
}

/* The node of vertex x to meet from pivot p in list L: p's predecessor, then
 * the node after p's successor, then any node in L, then a node in another
 * list; -1 when x has no node (it is full). */
static int32_t find_node(const struct rg *g, int32_t x, int32_t p, int32_t L)
{
    int32_t pred = g->nprev[p], after = g->nnext[g->nnext[p]];
    int32_t in_list = -1, other = -1;
    for (int32_t k = g->vhead[x]; k >= 0; k = g->nvnext[k]) {
        if (k == pred || k == after)
            return k;
        if (g->nlist[k] == L && in_list < 0)
            in_list = k;
        if (g->nlist[k] != L && other < 0)
            other = k;
    }
    return in_list >= 0 ? in_list : other;
}

/* The pivot to use at node p: p itself, or, when p is a dummy vertex, the
 * first real vertex before it. A dummy vertex as pivot would conquer its
 * whole boundary loop at once and leave a band of free triangles between
 * the loop and the front that later splits into many lists; skipped, its
 * triangles are conquered from the boundary vertices' fans as the front
 * reaches them. */
static int32_t pivot_from(const struct rg *g, int32_t p)
{
    int32_t q = p;
    while (g->nv_[q] >= g->nv) {
        q = g->nprev[q];
        if (q == p)
            return p; /* only dummies: one must be the pivot */
    }
    return q;
}

/* Alliez and Desbrun pick the pivot with the fewest free edges to avoid
 * splits; a local form of that rule: when the pivot's predecessor a has one
 * free triangle left, across the gate (a, p), and it closes a's fan (its
 * third vertex precedes a), that triangle is conquered first and a leaves
 * the list. Without it an irregular mesh's front keeps such notches behind
 * the pivot, and the pivot's next triangle splits them off. Returns whether
 * it conquered. */
static bool close_ear(struct rg *g, int32_t L, int32_t p)
{
    int32_t a = g->nprev[p], b = g->nprev[a];
    if (g->llen[L] <= 3)
        return false;
    int32_t t = xacross(g, g->ngate[a], g->nv_[a], g->nv_[p]);
    if (t < 0 || g->tconq[t])
        violated("the triangle across gate (%" PRId32 ", %" PRId32 ") is not free", g->nv_[a], g->nv_[p]);
    for (int i = 0; i < 3; i++)
        if (xvert(g, t, i) == g->nv_[b]) {
            g->tconq[t] = 1;
            g->nnext[b] = p;
            g->nprev[p] = b;
            g->ngate[b] = t;
            free_node(g, a);
            g->llen[L]--;
            return true;
        }
    return false;
}

/* Conquers the region list L borders. */
static void run_list(struct rg *g, int32_t L)
{
    char code[48];
    int32_t p = g->lfront[L];
    while (g->llen[L] > 2) {
        p = pivot_from(g, p);
        if (close_ear(g, L, p))
            continue;
        int32_t n = g->nnext[p];
        int32_t t = xacross(g, g->ngate[p], g->nv_[p], g->nv_[n]);
        if (t < 0 || g->tconq[t])
            violated("the triangle across gate (%" PRId32 ", %" PRId32 ") is not free", g->nv_[p], g->nv_[n]);
        g->tconq[t] = 1;
        int32_t x = -1;
        for (int i = 0; i < 3; i++) {
            int32_t w = xvert(g, t, i);
            if (w != g->nv_[p] && w != g->nv_[n])
                x = w;
        }
        if (!g->vconq[x]) {
            conquer_vertex(g, x);
            int32_t k = new_node(g, x, L);
            link_between(g, k, p, n);
            g->ngate[p] = t;
            g->ngate[k] = t;
            g->llen[L]++;
            continue;
        }
        int32_t X = find_node(g, x, p, L);
        if (X < 0)
            violated("vertex %" PRId32 " is full but triangle %" PRId32 " is free", x, t);
        int32_t a = g->nprev[p];
        if (X == a) { /* p's fan is closed: p is full */
            g->nnext[a] = n;
            g->nprev[n] = a;
            g->ngate[a] = t;
            free_node(g, p);
            g->llen[L]--;
            p = a;
        } else if (X == g->nnext[n]) { /* n's fan is closed */
            g->nnext[p] = X;
            g->nprev[X] = p;
            g->ngate[p] = t;
            free_node(g, n);
            g->llen[L]--;
        } else if (g->nlist[X] == L) { /* split: n .. before X, plus a new node of x */
            int32_t L2 = new_list(g);
            int32_t y = g->nprev[X], k = 0;
            for (int32_t u = n;; u = g->nnext[u]) {
                g->nlist[u] = L2;
                k++;
                if (u == y)
                    break;
            }
            int32_t xn = new_node(g, x, L2);
            link_between(g, xn, y, n);
            g->ngate[xn] = t;
            g->nnext[p] = X;
            g->nprev[X] = p;
            g->ngate[p] = t;
            g->llen[L] -= k;
            g->llen[L2] = k + 1;
            g->lfront[L2] = n;
            push(g, L2);
            g->splits++;
            snprintf(code, sizeof code, "S%" PRId32, k + 1);
            emit(g, code);
        } else { /* merge with a stacked list M */
            int32_t M = g->nlist[X], offset = 0, stackpos = 0;
            for (int32_t u = g->lfront[M]; u != X; u = g->nnext[u])
                offset++;
            for (int32_t s = g->depth - 1; s >= 0 && g->stack[s] != M; s--)
                if (g->lalive[g->stack[s]])
                    stackpos++;
            int32_t u = X;
            do {
                g->nlist[u] = L;
                u = g->nnext[u];
            } while (u != X);
            int32_t y = g->nprev[X];
            int32_t xn = new_node(g, x, L);
            link_between(g, xn, y, n);
            g->ngate[xn] = t;
            g->nnext[p] = X;
            g->nprev[X] = p;
            g->ngate[p] = t;
            g->llen[L] += g->llen[M] + 1;
            g->lalive[M] = 0;
            g->merges++;
            snprintf(code, sizeof code, "M%" PRId32 ",%" PRId32, stackpos, offset);
            emit(g, code);
        }
    }
    /* The two nodes left enclose nothing. */
    int32_t q = g->nnext[p];
    free_node(g, p);
    if (q != p)
        free_node(g, q);
    g->lalive[L] = 0;
}

/* ---- Program 4.2: the breadth-first conquest -------------------------------- */

struct fifo {
    const struct Mesh *m;
    int32_t *free_tris;   /* per conquered vertex: its triangles not yet conquered */
    unsigned char *tconq, *vconq, *inlist, *stacked;
    int32_t *queue;       /* the active list: [head, tail) */
    size_t head, tail, cap;
    int32_t *stack;       /* pushed lists: single vertices, and component seeds */
    size_t depth;
    int32_t *fan;
    size_t fan_cap;
    uint64_t codes, splits, valence_sum, checksum;
    bool print;
};

static void fifo_push_back(struct fifo *f, int32_t v)
{
    if (f->tail == f->cap) {
        f->cap = f->cap ? 2 * f->cap : 1024;
        f->queue = xrealloc(f->queue, f->cap * sizeof *f->queue);
    }
    f->queue[f->tail++] = v;
    f->inlist[v] = 1;
}

/* The fan of v into f->fan; returns its size. */
static size_t fifo_fan(struct fifo *f, int32_t v, bool *open)
{
    size_t n = vertex_fan(f->m, v, f->fan, f->fan_cap, open);
    if (n > f->fan_cap) {
        f->fan_cap = n;
        f->fan = xrealloc(f->fan, n * sizeof *f->fan);
        n = vertex_fan(f->m, v, f->fan, f->fan_cap, open);
    }
    return n;
}

/* Conquers v: its valence (its triangles, counted around its fan, next to
 * the focus) is the code, and its free triangles are counted for "full". */
static void fifo_conquer(struct fifo *f, int32_t v)
{
    char code[32];
    bool open;
    size_t n = fifo_fan(f, v, &open);
    int32_t free_tris = 0;
    for (size_t i = 0; i < n; i++)
        free_tris += !f->tconq[f->fan[i]];
    f->vconq[v] = 1;
    f->free_tris[v] = free_tris;
    snprintf(code, sizeof code, "A%zu", n);
    f->codes++;
    f->valence_sum += n;
    f->checksum = fnv1a64_line(f->checksum, code);
    if (f->print)
        printf("%s\n", code);
    fifo_push_back(f, v);
}

/* The focus's incident vertices, in rotation order: around its fan, the
 * vertex after it in each triangle, and for an open fan the last one's
 * other vertex too. Each triangle of the fan is conquered. */
static void fifo_focus(struct fifo *f, int32_t focus)
{
    const struct Mesh *m = f->m;
    bool open;
    size_t n = fifo_fan(f, focus, &open);
    /* The fan is walked again by the conquests below: keep this one. */
    int32_t *fan = xmalloc(n * sizeof *fan);
    memcpy(fan, f->fan, n * sizeof *fan);
    for (size_t i = 0; i < n + (open && n ? 1 : 0); i++) {
        int32_t ti = fan[i < n ? i : n - 1];
        const struct Triangle *t = &m->triangles[ti];
        int k = tri_corner(t, focus);
        int32_t v = t->vertexIndices[(k + (i < n ? 1 : 2)) % 3];
        if (i < n && !f->tconq[ti]) {
            f->tconq[ti] = 1;
            for (int c = 0; c < 3; c++)
                if (f->vconq[t->vertexIndices[c]])
                    f->free_tris[t->vertexIndices[c]]--;
        }
        if (!f->vconq[v]) {
            fifo_conquer(f, v);
        } else if (f->inlist[v] && f->free_tris[v] > 0 && !f->stacked[v]) {
            /* The conquest meets its own front: a second list, for later. */
            f->stacked[v] = 1;
            f->stack[f->depth++] = v;
            f->splits++;
        }
    }
    free(fan);
}

static int run_fifo(const struct Mesh *m, bool print, const struct workload_args *args,
                    double t0, double t1)
{
    struct fifo f;
    memset(&f, 0, sizeof f);
    f.m = m;
    f.print = print;
    f.checksum = FNV1A64_INIT;
    size_t nv = m->verNr, nt = m->triNr;
    f.free_tris = xmalloc(nv * sizeof *f.free_tris);
    f.vconq = xmalloc(nv);
    f.inlist = xmalloc(nv);
    f.stacked = xmalloc(nv);
    f.tconq = xmalloc(nt);
    f.stack = xmalloc((nv + nt) * sizeof *f.stack);
    memset(f.vconq, 0, nv);
    memset(f.inlist, 0, nv);
    memset(f.stacked, 0, nv);
    memset(f.tconq, 0, nt);
    f.fan_cap = 64;
    f.fan = xmalloc(f.fan_cap * sizeof *f.fan);

    for (size_t s = 0; s < nt; s++) {
        if (f.tconq[s])
            continue;
        /* A seed: its vertices start the active list. */
        for (int c = 0; c < 3; c++) {
            int32_t v = m->triangles[s].vertexIndices[c];
            if (!f.vconq[v])
                fifo_conquer(&f, v);
        }
        for (;;) {
            while (f.head < f.tail) {
                int32_t focus = f.queue[f.head++];
                f.inlist[focus] = 0;
                fifo_focus(&f, focus);
            }
            /* The next list from the stack; one whose vertex is full by
             * now encloses nothing and is dropped, as Touma and Gotsman drop
             * a list of two vertices. */
            while (f.depth > 0 && f.free_tris[f.stack[f.depth - 1]] == 0)
                f.depth--;
            if (f.depth == 0)
                break;
            f.head = f.tail = 0;
            fifo_push_back(&f, f.stack[--f.depth]);
        }
        f.head = f.tail = 0;
    }

    /* The invariants, from the program's own flags (a sweep over the mesh
     * here would be part of the traversal emm simulates): every triangle
     * conquered, so every vertex of one; each vertex conquered once (a flag)
     * with its whole fan, so the valences add up to 3 x triangles. */
    int64_t conquered = 0;
    for (size_t v = 0; v < nv; v++)
        conquered += f.vconq[v];
    for (size_t t = 0; t < nt; t++)
        if (!f.tconq[t])
            violated("triangle %zu never reached", t);
    if (f.valence_sum != 3 * (uint64_t)nt)
        violated("valences add up to %" PRIu64 ", not 3 * %zu triangles", f.valence_sum, nt);
    if ((uint64_t)conquered != f.codes)
        violated("%" PRIu64 " codes for %" PRId64 " vertices", f.codes, conquered);
    double t2 = workload_now();
    printf("codes: %" PRIu64 "\nsplits: %" PRIu64 "\nchecksum: 0x%016" PRIx64 "\n", f.codes,
           f.splits, f.checksum);
    workload_report_times(args, t0, t1, t2);
    free(f.free_tris);
    free(f.vconq);
    free(f.inlist);
    free(f.stacked);
    free(f.tconq);
    free(f.queue);
    free(f.stack);
    free(f.fan);
    return 0;
}

int main(int argc, char **argv)
{
    struct workload_args args = {NULL, false};
    bool print = false, conquest = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0) {
            usage(stdout);
            return 0;
        } else if (strcmp(a, "--print-codes") == 0) {
            print = true;
        } else if (strcmp(a, "--conquest") == 0) {
            conquest = true;
        } else {
            int rc = workload_common_arg(&args, PROG, a);
            if (rc)
                return rc;
        }
    }

    double t0 = workload_now();
    struct Mesh mesh;
    if (!read_mesh(PROG, args.mesh, &mesh))
        return 1;
    double t1 = workload_now();
    if (!conquest) {
        int rc = run_fifo(&mesh, print, &args, t0, t1);
        free_mesh(&mesh);
        return rc;
    }

    struct rg g;
    memset(&g, 0, sizeof g);
    g.m = &mesh;
    g.nv = (int32_t)mesh.verNr;
    g.nt = (int32_t)mesh.triNr;
    g.free_node = -1;
    g.checksum = FNV1A64_INIT;
    g.print = print;
    close_boundaries(&g);
    g.tconq = xmalloc((size_t)g.NT);
    memset(g.tconq, 0, (size_t)g.NT);
    g.vconq = xmalloc((size_t)g.NV * sizeof *g.vconq);
    memset(g.vconq, 0, (size_t)g.NV * sizeof *g.vconq);
    g.vhead = xmalloc((size_t)g.NV * sizeof *g.vhead);
    for (int32_t v = 0; v < g.NV; v++)
        g.vhead[v] = -1;

    int64_t components = 0;
    for (int32_t s = 0; s < g.nt; s++) {
        if (g.tconq[s])
            continue;
        components++;
        int32_t L = new_list(&g), nodes[3];
        for (int i = 0; i < 3; i++) {
            int32_t v = mesh.triangles[s].vertexIndices[i];
            if (g.vconq[v])
                violated("seed triangle %" PRId32 " has conquered vertex %" PRId32, s, v);
            conquer_vertex(&g, v);
            nodes[i] = new_node(&g, v, L);
        }
        for (int i = 0; i < 3; i++) {
            g.nnext[nodes[i]] = nodes[(i + 1) % 3];
            g.nprev[nodes[i]] = nodes[(i + 2) % 3];
            g.ngate[nodes[i]] = s;
        }
        g.tconq[s] = 1;
        g.llen[L] = 3;
        g.lfront[L] = nodes[0];
        push(&g, L);
        while (g.depth > 0) {
            int32_t top = g.stack[--g.depth];
            if (g.lalive[top])
                run_list(&g, top);
        }
    }

    /* The invariants. */
    int64_t conquered = 0;
    for (int32_t v = 0; v < g.NV; v++) {
        bool isolated = v < g.nv && mesh.vertices[v].vfConnec[0] < 0;
        uint32_t want = isolated ? 0 : 1;
        if (g.vconq[v] != want)
            violated("vertex %" PRId32 " conquered %" PRIu32 " times", v, g.vconq[v]);
        conquered += want;
    }
    for (int32_t t = 0; t < g.NT; t++)
        if (!g.tconq[t])
            violated("triangle %" PRId32 " never reached", t);
    if (g.live_nodes != 0)
        violated("%" PRId32 " list nodes left at the end", g.live_nodes);
    if (g.valence_sum != 3 * (uint64_t)g.NT)
        violated("valences add up to %" PRIu64 ", not 3 * %" PRId32 " triangles", g.valence_sum, g.NT);
    if ((uint64_t)conquered + g.splits + g.merges != g.codes)
        violated("%" PRIu64 " codes for %" PRId64 " vertices, splits and merges", g.codes, conquered);
    /* Euler: V - E + F = V - NT/2 = sum over components of 2 - 2 genus. */
    int64_t chi2 = 2 * conquered - g.NT; /* twice the Euler characteristic */
    int64_t genus2 = 4 * components - chi2; /* four times the total genus */
    if (genus2 < 0 || genus2 % 4 != 0 || (uint64_t)(genus2 / 4) != g.merges)
        violated("%" PRIu64 " merges, but the Euler characteristic gives genus %" PRId64 "/4",
                 g.merges, genus2);
    double t2 = workload_now();

    printf("codes: %" PRIu64 "\nsplits: %" PRIu64 "\nmerges: %" PRIu64 "\nchecksum: 0x%016" PRIx64 "\n",
           g.codes, g.splits, g.merges, g.checksum);
    workload_report_times(&args, t0, t1, t2);

    free(g.bnd);
    free(g.dv);
    free(g.dn);
    free(g.loop_len);
    free(g.tconq);
    free(g.vconq);
    free(g.vhead);
    free(g.nv_);
    free(g.nnext);
    free(g.nprev);
    free(g.nlist);
    free(g.ngate);
    free(g.nvnext);
    free(g.lfront);
    free(g.llen);
    free(g.lalive);
    free(g.stack);
    free_mesh(&mesh);
    return 0;
}

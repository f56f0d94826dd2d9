/* A mesh converter of the shape users run under emm: it loads an OFF or OBJ
 * mesh into two arrays grown with realloc (vertices: three floats, 12-byte
 * records; faces: three uint32 vertex indices, 12-byte records), reads the
 * mesh once, in index order, to write another format, and exits. It knows
 * nothing of emm.
 *
 *   OUT.stl  binary STL: each face's corners and its normal, computed from
 *            the vertices (face i, then its three vertices)
 *   OUT.off  OFF text: every vertex in order, then every face (one
 *            index-order sweep of both arrays)
 *
 * Tagged by EMM_TAG rules (README "Tagging a program you did not write"):
 *   vertices:site=load_vertices,stride=12,xyz=0:f32;
 *   triangles:site=load_faces,stride=12,vidx=0:u32
 *
 * --faces-first: the loader reads the faces into their array before the
 *   vertices' array exists (a second pass over the file reads the vertices),
 *   as encoders that read connectivity first do.
 * --late: before converting, the program reads its vertices in a scattered
 *   order (a centroid over 8 passes), then copies the faces into a new array
 *   (late_faces) and converts from that copy: a rule naming late_faces tags
 *   its triangles long after the profile window.
 *
 * usage: convert_once [--faces-first] [--late] IN.off|IN.obj OUT.stl|OUT.off */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct mesh {
    float *v;      /* 3 per vertex */
    uint32_t *f;   /* 3 per face */
    size_t nv, nf; /* in use */
    size_t cv, cf; /* allocated */
} mesh;

/* Grows the vertex array by one record (doubling): the allocation site
 * the vertex rule names. */
static __attribute__((noinline)) int load_vertices(mesh *m, const float *p)
{
    if (m->nv == m->cv) {
        size_t cap = m->cv ? 2 * m->cv : 1024;
        float *grown = realloc(m->v, cap * 3 * sizeof *grown);
        if (!grown)
            return -1;
        m->v = grown;
        m->cv = cap;
    }
    memcpy(m->v + 3 * m->nv++, p, 3 * sizeof *p);
    return 0;
}

/* Grows the face array by one record: the site the triangle rule names. */
static __attribute__((noinline)) int load_faces(mesh *m, const uint32_t *idx)
{
    if (m->nf == m->cf) {
        size_t cap = m->cf ? 2 * m->cf : 1024;
        uint32_t *grown = realloc(m->f, cap * 3 * sizeof *grown);
        if (!grown)
            return -1;
        m->f = grown;
        m->cf = cap;
    }
    memcpy(m->f + 3 * m->nf++, idx, 3 * sizeof *idx);
    return 0;
}

static int ends_with(const char *s, const char *tail)
{
    size_t n = strlen(s), t = strlen(tail);
    return n >= t && strcmp(s + n - t, tail) == 0;
}

/* One pass over the file, keeping the vertices (want_v) and/or the faces
 * (want_f); 0 on success, else a message on stderr naming the file. */
static int read_pass(const char *path, mesh *m, int want_v, int want_f)
{
    FILE *in = fopen(path, "r");
    if (!in) {
        fprintf(stderr, "convert_once: %s: cannot open\n", path);
        return -1;
    }
    int obj = ends_with(path, ".obj"), rc = -1;
    char line[1024];
    size_t lineno = 0, nv = 0, nf = 0, seen_v = 0, seen_f = 0;
    if (!obj) {
        /* OFF: the keyword, then the counts. */
        if (!fgets(line, sizeof line, in) || strncmp(line, "OFF", 3) != 0) {
            fprintf(stderr, "convert_once: %s: not an OFF file (no OFF keyword)\n", path);
            goto done;
        }
        lineno = 1;
        do {
            if (!fgets(line, sizeof line, in)) {
                fprintf(stderr, "convert_once: %s: no vertex and face counts\n", path);
                goto done;
            }
            lineno++;
        } while (line[0] == '#' || line[0] == '\n');
        if (sscanf(line, "%zu %zu", &nv, &nf) != 2) {
            fprintf(stderr, "convert_once: %s:%zu: expected the vertex and face counts\n", path,
                    lineno);
            goto done;
        }
    }
    while (fgets(line, sizeof line, in)) {
        lineno++;
        if (line[0] == '#' || line[0] == '\n')
            continue;
        int is_v, is_f;
        const char *p = line;
        if (obj) {
            is_v = line[0] == 'v' && line[1] == ' ';
            is_f = line[0] == 'f' && line[1] == ' ';
            p = line + 2;
        } else {
            is_v = seen_v < nv;
            is_f = !is_v && seen_f < nf;
        }
        if (is_v) {
            float x[3];
            if (sscanf(p, "%f %f %f", &x[0], &x[1], &x[2]) != 3) {
                fprintf(stderr, "convert_once: %s:%zu: a vertex needs three coordinates\n",
                        path, lineno);
                goto done;
            }
            seen_v++;
            if (want_v && load_vertices(m, x) != 0)
                goto nomem;
        } else if (is_f) {
            long long k[3];
            int count = 3, ok;
            if (obj) {
                /* f a b c, each a, a/t, a//n or a/t/n, 1-based */
                char *q = (char *)p, *end;
                ok = 1;
                for (int c = 0; c < 3 && ok; c++) {
                    k[c] = strtoll(q, &end, 10) - 1;
                    ok = end != q;
                    q = end;
                    while (*q && *q != ' ' && *q != '\t' && *q != '\n')
                        q++;
                }
            } else {
                ok = sscanf(p, "%d %lld %lld %lld", &count, &k[0], &k[1], &k[2]) == 4;
            }
            if (!ok || count != 3) {
                fprintf(stderr, "convert_once: %s:%zu: a face needs three vertex indices "
                                "(only triangles are converted)\n",
                        path, lineno);
                goto done;
            }
            seen_f++;
            uint32_t idx[3];
            for (int c = 0; c < 3; c++) {
                if (k[c] < 0 || k[c] > UINT32_MAX) {
                    fprintf(stderr, "convert_once: %s:%zu: vertex index %lld out of range\n",
                            path, lineno, k[c] + obj);
                    goto done;
                }
                idx[c] = (uint32_t)k[c];
            }
            if (want_f && load_faces(m, idx) != 0)
                goto nomem;
        }
    }
    if (!obj && (seen_v < nv || seen_f < nf)) {
        fprintf(stderr, "convert_once: %s: %zu of %zu vertices and %zu of %zu faces\n", path,
                seen_v, nv, seen_f, nf);
        goto done;
    }
    rc = 0;
    goto done;
nomem:
    fprintf(stderr, "convert_once: %s: out of memory\n", path);
done:
    fclose(in);
    return rc;
}

/* The copy the --late mode converts from: a new block, allocated here
 * (the site a late rule names), after the vertices were read a while. */
static __attribute__((noinline)) uint32_t *late_faces(const mesh *m)
{
    uint32_t *copy = malloc(m->nf * 3 * sizeof *copy);
    if (copy)
        memcpy(copy, m->f, m->nf * 3 * sizeof *copy);
    return copy;
}

static void put_u32(unsigned char *p, uint32_t x)
{
    p[0] = (unsigned char)x;
    p[1] = (unsigned char)(x >> 8);
    p[2] = (unsigned char)(x >> 16);
    p[3] = (unsigned char)(x >> 24);
}

/* A face that names a vertex the file does not have: checked as it is
 * written (the mesh is read once). */
static int bad_face(const mesh *m, size_t i, const uint32_t *t)
{
    fprintf(stderr, "convert_once: face %zu names vertex %u, %u or %u of %zu\n", i, t[0], t[1],
            t[2], m->nv);
    return -2;
}

/* Binary STL: face i, then its three vertices, once each, in order. */
static int write_stl(FILE *out, const mesh *m, const uint32_t *faces)
{
    unsigned char header[84] = "binary STL written by convert_once";
    put_u32(header + 80, (uint32_t)m->nf);
    if (fwrite(header, 1, sizeof header, out) != sizeof header)
        return -1;
    for (size_t i = 0; i < m->nf; i++) {
        const uint32_t *t = faces + 3 * i;
        float c[3][3], n[3], rec[12];
        if (t[0] >= m->nv || t[1] >= m->nv || t[2] >= m->nv)
            return bad_face(m, i, t);
        for (int k = 0; k < 3; k++)
            memcpy(c[k], m->v + 3 * (size_t)t[k], sizeof c[k]);
        float a[3] = {c[1][0] - c[0][0], c[1][1] - c[0][1], c[1][2] - c[0][2]};
        float b[3] = {c[2][0] - c[0][0], c[2][1] - c[0][1], c[2][2] - c[0][2]};
        n[0] = a[1] * b[2] - a[2] * b[1];
        n[1] = a[2] * b[0] - a[0] * b[2];
        n[2] = a[0] * b[1] - a[1] * b[0];
        float len = sqrtf(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++)
            n[k] = len > 0 ? n[k] / len : 0;
        memcpy(rec, n, sizeof n);
        memcpy(rec + 3, c, sizeof c);
        unsigned char attr[2] = {0, 0};
        if (fwrite(rec, sizeof rec, 1, out) != 1 || fwrite(attr, 1, 2, out) != 2)
            return -1;
    }
    return 0;
}

/* OFF text: the vertices in order, then the faces: one sweep. */
static int write_off(FILE *out, const mesh *m, const uint32_t *faces)
{
    fprintf(out, "OFF\n%zu %zu 0\n", m->nv, m->nf);
    for (size_t i = 0; i < m->nv; i++)
        fprintf(out, "%.9g %.9g %.9g\n", m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]);
    for (size_t i = 0; i < m->nf; i++) {
        const uint32_t *t = faces + 3 * i;
        if (t[0] >= m->nv || t[1] >= m->nv || t[2] >= m->nv)
            return bad_face(m, i, t);
        fprintf(out, "3 %u %u %u\n", t[0], t[1], t[2]);
    }
    return ferror(out) ? -1 : 0;
}

int main(int argc, char **argv)
{
    int faces_first = 0, late = 0, i = 1;
    for (; i < argc && argv[i][0] == '-' && argv[i][1] == '-'; i++) {
        if (strcmp(argv[i], "--faces-first") == 0)
            faces_first = 1;
        else if (strcmp(argv[i], "--late") == 0)
            late = 1;
        else {
            fprintf(stderr, "convert_once: unknown option %s\n", argv[i]);
            return 2;
        }
    }
    if (argc - i != 2 || !(ends_with(argv[i + 1], ".stl") || ends_with(argv[i + 1], ".off"))) {
        fprintf(stderr, "usage: convert_once [--faces-first] [--late] IN.off|IN.obj "
                        "OUT.stl|OUT.off\n");
        return 2;
    }
    const char *in = argv[i], *outpath = argv[i + 1];
    mesh m = {0};
    int rc = faces_first ? read_pass(in, &m, 0, 1) || read_pass(in, &m, 1, 0)
                         : read_pass(in, &m, 1, 1);
    if (rc != 0)
        return 1;
    const uint32_t *faces = m.f;
    uint32_t *copy = NULL;
    if (late) {
        /* The vertices first, scattered (a stride prime to the count). */
        double sum[3] = {0, 0, 0};
        size_t step = 7919 % (m.nv ? m.nv : 1) ? 7919 : 1;
        for (int pass = 0; pass < 8; pass++)
            for (size_t k = 0, v = 0; k < m.nv; k++, v = (v + step) % m.nv)
                for (int c = 0; c < 3; c++)
                    sum[c] += m.v[3 * v + (size_t)c];
        printf("convert_once: centroid %.6f %.6f %.6f\n", sum[0] / (8.0 * (double)m.nv),
               sum[1] / (8.0 * (double)m.nv), sum[2] / (8.0 * (double)m.nv));
        if (!(copy = late_faces(&m))) {
            fprintf(stderr, "convert_once: out of memory\n");
            return 1;
        }
        faces = copy;
    }
    FILE *out = fopen(outpath, "wb");
    if (!out) {
        fprintf(stderr, "convert_once: %s: cannot create\n", outpath);
        return 1;
    }
    rc = ends_with(outpath, ".stl") ? write_stl(out, &m, faces) : write_off(out, &m, faces);
    if (fclose(out) != 0 || rc != 0) {
        if (rc != -2)
            fprintf(stderr, "convert_once: %s: write failed\n", outpath);
        return 1;
    }
    printf("convert_once: %zu vertices, %zu faces -> %s\n", m.nv, m.nf, outpath);
    free(copy);
    free(m.v);
    free(m.f);
    return 0;
}

/* runtime/outfile.c: the temporary file, its mode, commit, abort and the
 * failures that must leave nothing behind. */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "check.h"
#include "outfile.h"

static char dir[64];

/* Entries of dir other than . and .. */
static int entries(void)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static char *slurp(const char *path)
{
    static char buf[256];
    FILE *f = fopen(path, "r");
    if (!f)
        return NULL;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static int has(const char *s, const char *sub) { return strstr(s, sub) != NULL; }

static void test_commit_and_mode(void)
{
    char path[128];
    snprintf(path, sizeof path, "%s/a.txt", dir);
    static const mode_t masks[] = {022, 077, 002};
    for (size_t i = 0; i < sizeof masks / sizeof *masks; i++) {
        mode_t old = umask(masks[i]);
        emm_outfile o;
        emm_error err;
        REQUIRE(emm_outfile_open(&o, path, "the test", &err) == EMM_OK);
        CHECK(strncmp(o.tmp, path, strlen(path)) == 0 && has(o.tmp, ".tmp."));
        fprintf(o.f, "hello %zu\n", i);
        CHECK(access(path, F_OK) != 0 || i > 0); /* not there before commit */
        REQUIRE(emm_outfile_commit(&o, "the test", &err) == EMM_OK);
        umask(old);
        struct stat st;
        REQUIRE(stat(path, &st) == 0);
        CHECKF((st.st_mode & 0777) == (0666 & ~masks[i]), "mode %o under umask %o",
               (unsigned)(st.st_mode & 0777), (unsigned)masks[i]);
        char want[32];
        snprintf(want, sizeof want, "hello %zu\n", i);
        const char *got = slurp(path);
        CHECK(got && strcmp(got, want) == 0);
        CHECK(entries() == 1);
        CHECK(o.f == NULL && o.tmp == NULL && o.path == NULL);
    }
    remove(path);
}

/* Two writers of one path at once (two threads, or a retry) get their own
 * temporary files; the old file stays whole until a commit replaces it. */
static void test_two_at_once(void)
{
    char path[128];
    snprintf(path, sizeof path, "%s/b.txt", dir);
    FILE *f = fopen(path, "w");
    REQUIRE(f);
    fputs("old\n", f);
    fclose(f);
    emm_outfile a, b;
    emm_error err;
    REQUIRE(emm_outfile_open(&a, path, "the test", &err) == EMM_OK);
    REQUIRE(emm_outfile_open(&b, path, "the test", &err) == EMM_OK);
    CHECK(strcmp(a.tmp, b.tmp) != 0);
    fputs("first\n", a.f);
    fputs("second\n", b.f);
    CHECK(entries() == 3);
    const char *got = slurp(path);
    CHECK(got && strcmp(got, "old\n") == 0);
    REQUIRE(emm_outfile_commit(&a, "the test", &err) == EMM_OK);
    got = slurp(path);
    CHECK(got && strcmp(got, "first\n") == 0);
    REQUIRE(emm_outfile_commit(&b, "the test", &err) == EMM_OK);
    got = slurp(path);
    CHECK(got && strcmp(got, "second\n") == 0);
    CHECK(entries() == 1);
    remove(path);
}

static void test_abort(void)
{
    char path[128];
    snprintf(path, sizeof path, "%s/c.txt", dir);
    emm_outfile o = {0};
    emm_outfile_abort(&o); /* zeroed: nothing to do */
    emm_error err;
    REQUIRE(emm_outfile_open(&o, path, "the test", &err) == EMM_OK);
    fputs("never\n", o.f);
    CHECK(entries() == 1);
    emm_outfile_abort(&o);
    CHECK(entries() == 0);
    emm_outfile_abort(&o); /* twice is harmless */
    CHECK(access(path, F_OK) != 0);
}

static void test_failures(void)
{
    emm_outfile o;
    emm_error err;
    char path[160];

    /* A directory that does not exist: refused at open, named. */
    snprintf(path, sizeof path, "%s/missing/d.txt", dir);
    CHECK(emm_outfile_open(&o, path, "the widget", &err) == EMM_ERR_IO);
    CHECKF(has(err.message, path) && has(err.message, "cannot write the widget") &&
               has(err.message, strerror(ENOENT)),
           "%s", err.message);
    emm_outfile_abort(&o); /* safe after a failed open */

    /* A write that failed (the stream's error flag) fails the commit and
     * leaves nothing: reading a write-only stream sets that flag. */
    snprintf(path, sizeof path, "%s/e.txt", dir);
    REQUIRE(emm_outfile_open(&o, path, "the widget", &err) == EMM_OK);
    fputs("half\n", o.f);
    CHECK(fgetc(o.f) == EOF && ferror(o.f));
    CHECK(emm_outfile_commit(&o, "the widget", &err) == EMM_ERR_IO);
    CHECKF(has(err.message, path) && has(err.message, "cannot write the widget"), "%s",
           err.message);
    CHECK(access(path, F_OK) != 0);
    CHECK(entries() == 0);
    emm_outfile_abort(&o); /* safe after a failed commit */

    /* The directory disappears before the commit: the rename fails. */
    char sub[96];
    snprintf(sub, sizeof sub, "%s/gone", dir);
    REQUIRE(mkdir(sub, 0755) == 0);
    snprintf(path, sizeof path, "%s/f.txt", sub);
    REQUIRE(emm_outfile_open(&o, path, "the widget", &err) == EMM_OK);
    fputs("lost\n", o.f);
    REQUIRE(unlink(o.tmp) == 0 && rmdir(sub) == 0);
    CHECK(emm_outfile_commit(&o, "the widget", &err) == EMM_ERR_IO);
    CHECKF(has(err.message, path) && has(err.message, "cannot write the widget"), "%s",
           err.message);
    CHECK(access(path, F_OK) != 0);
}

int main(void)
{
    snprintf(dir, sizeof dir, "outfile-XXXXXX");
    REQUIRE(mkdtemp(dir) != NULL);
    test_commit_and_mode();
    test_two_at_once();
    test_abort();
    test_failures();
    CHECK(entries() == 0);
    rmdir(dir);
    return check_done();
}

/* Preloaded into record_writer by integration.record_kill: the process SIGKILLs itself just before its
 * K-th write to a file (K = $SPHFSI_KILL_AT_WRITE), so a test can stop a recording between any two of the
 * writes the recorder makes, one after another, instead of hoping a timed kill lands in a flush. Writes
 * are pwrite; the file is sized with ftruncate and fallocate: all three count. At exit, without a kill, it
 * prints how many there were ("writes: N") on stderr. With SPHFSI_FAIL_WRITES_FROM=K it does not kill: the
 * K-th write and every later one fail with ENOSPC, as on a disk that has just filled.
 *
 * Preloaded into sphfsi by integration.resume, it stops the coordinator at a rename instead: just before
 * (SPHFSI_KILL_AT_RENAME_WHEN=before) or just after (the default) the N-th rename (N =
 * $SPHFSI_KILL_AT_RENAME_COUNT, default 1) onto a path ending in $SPHFSI_KILL_AT_RENAME_TO, such as the
 * publishing of checkpoint.bin. With SPHFSI_KILL_AT_RENAME_WHEN=fail that rename fails instead (EIO, nothing
 * renamed) and the process goes on. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

static long writes;

/* Counts the write; 1 if it is to fail (errno is then ENOSPC). */
static int count_and_maybe_die(void) {
    static long kill_at = -1, fail_from = -1;
    if (kill_at < 0) {
        const char* k = getenv("SPHFSI_KILL_AT_WRITE");
        const char* f = getenv("SPHFSI_FAIL_WRITES_FROM");
        kill_at = k ? atol(k) : 0;
        fail_from = f ? atol(f) : 0;
    }
    if (++writes == kill_at) raise(SIGKILL);
    if (fail_from > 0 && writes >= fail_from) {
        errno = ENOSPC;
        return 1;
    }
    return 0;
}

#define FORWARD(name, ret, params, args)                                   \
    ret name params {                                                      \
        static ret(*real) params;                                          \
        if (!real) real = (ret(*) params)dlsym(RTLD_NEXT, #name);          \
        if (count_and_maybe_die()) return -1;                              \
        return real args;                                                  \
    }

FORWARD(pwrite, ssize_t, (int fd, const void* buf, size_t n, off_t at), (fd, buf, n, at))
FORWARD(pwrite64, ssize_t, (int fd, const void* buf, size_t n, off64_t at), (fd, buf, n, at))
FORWARD(ftruncate, int, (int fd, off_t size), (fd, size))
FORWARD(ftruncate64, int, (int fd, off64_t size), (fd, size))
FORWARD(fallocate, int, (int fd, int mode, off_t at, off_t n), (fd, mode, at, n))
FORWARD(fallocate64, int, (int fd, int mode, off64_t at, off64_t n), (fd, mode, at, n))

int rename(const char* from, const char* to) {
    static int (*real)(const char*, const char*);
    static long seen;
    if (!real) real = (int (*)(const char*, const char*))dlsym(RTLD_NEXT, "rename");
    const char* suffix = getenv("SPHFSI_KILL_AT_RENAME_TO");
    const char* count = getenv("SPHFSI_KILL_AT_RENAME_COUNT");
    const char* when = getenv("SPHFSI_KILL_AT_RENAME_WHEN");
    const size_t n = strlen(to), k = suffix ? strlen(suffix) : 0;
    const int chosen = suffix && n >= k && strcmp(to + n - k, suffix) == 0 && ++seen == (count ? atol(count) : 1);
    const int before = when && strcmp(when, "before") == 0;
    if (chosen && when && strcmp(when, "fail") == 0) {
        errno = EIO;
        return -1;
    }
    if (chosen && before) raise(SIGKILL);
    const int done = real(from, to);
    if (chosen) raise(SIGKILL);
    return done;
}

__attribute__((destructor)) static void report(void) { fprintf(stderr, "writes: %ld\n", writes); }

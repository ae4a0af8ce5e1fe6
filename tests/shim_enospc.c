/* shim_enospc.c — a test-only LD_PRELOAD library: one MPI rank's writes to
 * one file fail with ENOSPC after a number of bytes, as a disk that fills
 * part-way through a collective write does to the rank whose share lands
 * last (tests/test_fulldisk.sh). Not part of sphseg: built by that test.
 *
 *   SHIM_ENOSPC=RANK:NAME:BYTES LD_PRELOAD=shim_enospc.so mpirun ... sphseg ...
 *
 * On the rank whose OMPI_COMM_WORLD_RANK (or PMIX_RANK) is RANK, writes to
 * a file whose path ends in NAME fail with ENOSPC once BYTES bytes have been
 * written to such files (in all, over the run); other ranks and files are
 * untouched. write, pwrite, pwritev and writev (and their 64-bit names) are
 * covered: Open MPI's OMPIO and ROMIO write with these. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/uio.h>
#include <unistd.h>

static int shim_on = -1;
static char shim_name[256];
static long long shim_left;

static void shim_init(void)
{
    if (shim_on >= 0) return;
    shim_on = 0;
    const char *spec = getenv("SHIM_ENOSPC"), *rank = getenv("OMPI_COMM_WORLD_RANK");
    if (!rank) rank = getenv("PMIX_RANK");
    int want = -1;
    long long bytes = 0;
    if (!spec || sscanf(spec, "%d:%255[^:]:%lld", &want, shim_name, &bytes) != 3) return;
    if ((rank ? atoi(rank) : 0) != want) return;
    shim_left = bytes;
    shim_on = 1;
}

/* 1 when this write of n bytes to fd must fail. */
static int shim_fail(int fd, size_t n)
{
    shim_init();
    if (!shim_on) return 0;
    char link[64], path[4096];
    snprintf(link, sizeof link, "/proc/self/fd/%d", fd);
    ssize_t k = readlink(link, path, sizeof path - 1);
    if (k <= 0) return 0;
    path[k] = 0;
    size_t lp = strlen(path), ln = strlen(shim_name); /* the file itself, not Open MPI's files named after it */
    if (lp < ln || strcmp(path + lp - ln, shim_name) != 0) return 0;
    if (shim_left < (long long)n) {
        shim_left = 0;
        errno = ENOSPC;
        return 1;
    }
    shim_left -= (long long)n;
    return 0;
}

static size_t shim_iov_len(const struct iovec *iov, int cnt)
{
    size_t n = 0;
    for (int i = 0; i < cnt; ++i) n += iov[i].iov_len;
    return n;
}

#define SHIM_NEXT(name) ((__typeof__(&name))dlsym(RTLD_NEXT, #name))

ssize_t write(int fd, const void *b, size_t n)
{
    if (shim_fail(fd, n)) return -1;
    return SHIM_NEXT(write)(fd, b, n);
}

ssize_t pwrite(int fd, const void *b, size_t n, off_t off)
{
    if (shim_fail(fd, n)) return -1;
    return SHIM_NEXT(pwrite)(fd, b, n, off);
}

ssize_t pwrite64(int fd, const void *b, size_t n, off_t off)
{
    if (shim_fail(fd, n)) return -1;
    return SHIM_NEXT(pwrite64)(fd, b, n, off);
}

ssize_t writev(int fd, const struct iovec *iov, int cnt)
{
    if (shim_fail(fd, shim_iov_len(iov, cnt))) return -1;
    return SHIM_NEXT(writev)(fd, iov, cnt);
}

ssize_t pwritev(int fd, const struct iovec *iov, int cnt, off_t off)
{
    if (shim_fail(fd, shim_iov_len(iov, cnt))) return -1;
    return SHIM_NEXT(pwritev)(fd, iov, cnt, off);
}

ssize_t pwritev64(int fd, const struct iovec *iov, int cnt, off_t off)
{
    if (shim_fail(fd, shim_iov_len(iov, cnt))) return -1;
    return SHIM_NEXT(pwritev64)(fd, iov, cnt, off);
}

/* outdir.c — see outdir.h. */
#define _XOPEN_SOURCE 700 /* realpath */
#include "outdir.h"
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "core/error.h"
#include "mpi/comm.h"

#define OUTDIR_PATH_MAX 4200

static int outdir_lock_fd = -1; /* open for the run's lifetime: closing it would drop the lock */

/* Lock OUTDIR/sphseg.lock (rank 0); NULL or why not, into why. */
static const char *outdir_lock(const char *dir, char *why, size_t n)
{
    char path[OUTDIR_PATH_MAX];
    snprintf(path, sizeof path, "%s/sphseg.lock", dir);
    int fd = open(path, O_RDWR | O_CREAT, 0644);
    if (fd < 0) return snprintf(why, n, "-o %.500s: cannot create %.500s: %s", dir, path, strerror(errno)), why;
    struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
    if (fcntl(fd, F_SETLK, &fl) != 0) {
        if (errno == EACCES || errno == EAGAIN) {
            char who[128] = "";
            ssize_t got = pread(fd, who, sizeof who - 1, 0);
            who[got > 0 ? got : 0] = 0;
            who[strcspn(who, "\n")] = 0;
            close(fd);
            return snprintf(why, n, "-o %.400s: another sphseg run is writing there (it holds %.500s: %.100s); wait for it, "
                            "or choose another -o", dir, path, who[0] ? who : "no owner recorded"), why;
        }
        warning("cannot lock %s (%s): this file system has no locks, so a second run into %s would not be "
                "stopped", path, strerror(errno), dir);
    }
    outdir_lock_fd = fd;
    return NULL;
}

/* The lock file names its holder, for the message a second run gives. */
static void outdir_lock_owner(const char *dir)
{
    char host[256] = "?", who[320];
    gethostname(host, sizeof host - 1);
    int len = snprintf(who, sizeof who, "pid %ld on %s\n", (long)getpid(), host);
    if (ftruncate(outdir_lock_fd, 0) != 0 || pwrite(outdir_lock_fd, who, (size_t)len, 0) != len)
        warning("cannot write %s/sphseg.lock: %s", dir, strerror(errno));
}

/* A file of a run: checkpoints, diagnostics, the XDMF index, snapshots. */
static int outdir_is_run_file(const char *name)
{
    static const char *const fixed[] = {"checkpoint.h5", "checkpoint_prev.h5", "diagnostics.csv",
                                        "diagnostics.csv.part", "snapshots.xmf"};
    for (size_t k = 0; k < sizeof fixed / sizeof fixed[0]; ++k)
        if (!strcmp(name, fixed[k])) return 1;
    size_t len = strlen(name);
    return !strncmp(name, "snapshot_", 9) && len > 12 && !strcmp(name + len - 3, ".h5");
}

/* The run files in dir, listed into list (first few); their count.
 * remove: delete them (and their temporaries) instead. */
static int outdir_scan(const char *dir, int remove, char *list, size_t n)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int count = 0;
    list[0] = 0;
    for (struct dirent *e; (e = readdir(d));) {
        char base[NAME_MAX + 1];
        snprintf(base, sizeof base, "%s", e->d_name);
        size_t len = strlen(base);
        if (len > 4 && !strcmp(base + len - 4, ".tmp")) base[len - 4] = 0; /* a killed run's temporary */
        if (!outdir_is_run_file(base) && strcmp(e->d_name, "STOP")) continue;
        if (remove) {
            char path[OUTDIR_PATH_MAX];
            snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
            if (unlink(path) != 0) warning("--overwrite: cannot remove %s: %s", path, strerror(errno));
        } else if (!strcmp(base, e->d_name) && strcmp(base, "STOP") && count++ < 4) {
            size_t used = strlen(list);
            snprintf(list + used, n - used, "%s%s", used ? ", " : "", e->d_name);
        }
    }
    closedir(d);
    return count;
}

/* The directory part of file, resolved; 0 if it cannot be. */
static int outdir_same(const char *dir, const char *file)
{
    char a[PATH_MAX], b[PATH_MAX], fdir[OUTDIR_PATH_MAX];
    const char *slash = strrchr(file, '/');
    snprintf(fdir, sizeof fdir, "%.*s", slash ? (int)(slash - file) : 1, slash ? file : ".");
    return realpath(dir, a) && realpath(fdir, b) && !strcmp(a, b);
}

void outdir_claim(const char *dir, int overwrite, const char *restart_from)
{
    char why[1200], list[600];
    const char *bad = NULL;
    if (comm_rank() == 0) {
        bad = outdir_lock(dir, why, sizeof why);
        int own = restart_from && outdir_same(dir, restart_from);
        int n = bad || own ? 0 : outdir_scan(dir, 0, list, sizeof list);
        if (n && !overwrite)
            bad = why, snprintf(why, sizeof why, "-o %.300s holds another run (%.300s%s): continue it with --restart %.300s, "
                                "choose another -o, or give --overwrite to replace it", dir, list,
                                n > 4 ? ", ..." : "", dir);
        else if (n)
            outdir_scan(dir, 1, list, sizeof list), message("--overwrite: removed the earlier run's files in %s", dir);
        if (!bad) outdir_lock_owner(dir);
    }
    input_error_agree(bad);
}

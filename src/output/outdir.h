/* outdir.h — one run per output directory (DESIGN.md "Files a run writes").
 * A run holds OUTDIR/sphseg.lock locked (fcntl) for its lifetime, so a
 * second run into the same OUTDIR stops at once; the kernel drops the lock
 * when the process ends, however it ends. */
#ifndef SPHSEG_OUTDIR_H
#define SPHSEG_OUTDIR_H

/* Collective, after OUTDIR exists and before anything is written to it.
 * Exit 2 (one line from rank 0) when another live run holds the lock, or
 * when OUTDIR holds the files of another run (checkpoints, diagnostics,
 * snapshots) and this is neither a restart from OUTDIR's own checkpoint
 * (restart_from: the checkpoint file read, or NULL) nor allowed to replace
 * them (overwrite: they are removed). A file system without locks is a
 * warning. */
void outdir_claim(const char *dir, int overwrite, const char *restart_from);

#endif

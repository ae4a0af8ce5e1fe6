/* scene_keys_none.h — every row macro of the key table (src/scene/scene_keys.h)
 * defined to expand to nothing. No include guard: a file that expands the
 * table includes this before each expansion, then redefines (#undef,
 * #define) only the rows that expansion reads. */
#include "scene_keys_undef.h"
#define ENTRY(name, st, title)
#define END_ENTRY(name, st)
#define SECTION(sec, m, st)
#define END_SECTION(m)
#define KF(sec, m, st, k, req, def, lo, hi, open, when, doc)
#define KE(sec, m, st, k, type, strs, def, doc)
#define KU(sec, m, st, k, def, doc)
#define KS(sec, m, st, k, mn, mx, def, doc)
#define KV(sec, m, st, k, n, def, doc)
#define KL(sec, m, st, k, est, entry, max, doc)
#define EKF(sec, st, k, doc)
#define EKE(sec, st, k, type, strs, doc)
#define EKU(sec, st, k, doc)
#define EKS(sec, st, k, mn, mx, doc)
#define EKV(sec, st, k, n, doc)

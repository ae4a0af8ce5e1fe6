#ifndef SPHSEG_VERSION_H
#define SPHSEG_VERSION_H
#define SPHSEG_VERSION "0.1.0"
#endif

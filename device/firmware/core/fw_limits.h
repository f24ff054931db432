/* Compile-time capacity of the core. All storage is static and sized here (no malloc);
 * a port overrides these with -D to fit its RAM (see stm32g0/board.h). */
#ifndef FW_LIMITS_H
#define FW_LIMITS_H

#ifndef FW_MAX_CHANNELS
#define FW_MAX_CHANNELS 8
#endif

/* Jitter-buffer storage in u16 words: buffer_samples * channels must fit. */
#ifndef FW_STORE_WORDS
#define FW_STORE_WORDS (32768 * 8)
#endif

/* 1: keep a phase per stored sample; 0 for a port that drives amplitudes only. */
#ifndef FW_PHASES
#define FW_PHASES 1
#endif

/* PROTOCOL.md 2: a body is at most 4096 bytes; a receiver takes frames of up to 4113
 * stuffed bytes (4096 + 4096 / 254 + 1), which decode to at most 4112 bytes. */
#define FW_MAX_BODY 4096u
#define FW_MAX_STUFFED (FW_MAX_BODY + FW_MAX_BODY / 254u + 1u)
#define FW_RX_CAPACITY (FW_MAX_STUFFED - 1u)

/* Values per ForceReport (PROTOCOL.md 4.9): one report every FW_FORCE_PAIRS *
 * force_decimation samples. */
#ifndef FW_FORCE_PAIRS
#define FW_FORCE_PAIRS 10
#endif

/* Longest device name the Info answer carries. */
#define FW_NAME_MAX 32u

#endif

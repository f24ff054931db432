/* Strict UTF-8 check (no overlongs, no surrogates, at most U+10FFFF): the text fields of
 * Info and Error are UTF-8 (PROTOCOL.md 4.2, 4.7) and the reference decoder refuses a
 * frame whose text is not. */
#ifndef FW_UTF8_H
#define FW_UTF8_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

bool fw_utf8_valid(const uint8_t *s, size_t n);

#endif

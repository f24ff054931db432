/* CRC-32/ISO-HDLC, the zlib / Ethernet CRC (PROTOCOL.md 2). */
#ifndef FW_CRC32_H
#define FW_CRC32_H

#include <stddef.h>
#include <stdint.h>

#define FW_CRC32_INIT 0xFFFFFFFFu

/* Running form: start at FW_CRC32_INIT, finish with ~crc. */
uint32_t fw_crc32_update(uint32_t crc, const uint8_t *p, size_t n);
uint32_t fw_crc32_byte(uint32_t crc, uint8_t b);
uint32_t fw_crc32(const uint8_t *p, size_t n);

#endif

#include "crc32.h"

/* Half-byte table: 64 bytes of flash instead of 1 KiB, two lookups per byte. */
static const uint32_t nibble[16] = {
    0x00000000u, 0x1DB71064u, 0x3B6E20C8u, 0x26D930ACu, 0x76DC4190u, 0x6B6B51F4u,
    0x4DB26158u, 0x5005713Cu, 0xEDB88320u, 0xF00F9344u, 0xD6D6A3E8u, 0xCB61B38Cu,
    0x9B64C2B0u, 0x86D3D2D4u, 0xA00AE278u, 0xBDBDF21Cu,
};

uint32_t fw_crc32_byte(uint32_t crc, uint8_t b)
{
    crc ^= b;
    crc = (crc >> 4) ^ nibble[crc & 15u];
    return (crc >> 4) ^ nibble[crc & 15u];
}

uint32_t fw_crc32_update(uint32_t crc, const uint8_t *p, size_t n)
{
    while (n--)
        crc = fw_crc32_byte(crc, *p++);
    return crc;
}

uint32_t fw_crc32(const uint8_t *p, size_t n)
{
    return ~fw_crc32_update(FW_CRC32_INIT, p, n);
}

/* Checksums: CRC-16/XMODEM for HiPNUC frames, CRC-32 (IEEE, as zlib) for capture chunks. */
#ifndef MOCAP_CRC_H
#define MOCAP_CRC_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Continue a CRC-16/XMODEM (poly 0x1021, init 0x0000, no reflection, no xor-out). */
uint16_t crc16_xmodem_update(uint16_t crc, const uint8_t *data, size_t len);
/* CRC-32/ISO-HDLC (zlib's crc32): crc32_update(0, data, len) gives the standard value. */
uint32_t crc32_update(uint32_t crc, const uint8_t *data, size_t len);

#ifdef __cplusplus
}
#endif
#endif

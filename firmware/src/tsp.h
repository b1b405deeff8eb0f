/* TSP/1 framing (docs/PROTOCOL.md §2): CRC-16/MCRF4XX, COBS, frame encode and decode.
 * Portable C99 without avr-libc, so the same file builds for the AVR and natively for the
 * framing test against the host's decoder (tests/firmware). */
#ifndef TSP_H
#define TSP_H

#include <stddef.h>
#include <stdint.h>

#define TSP_VERSION 1
/* Longest body (ver..crc), bytes; a wire frame is at most 254 bytes before its delimiter. */
#define TSP_MAX_BODY 253

/* Device -> host types. */
#define TSP_HELLO 0x41
#define TSP_SAMPLE 0x42
#define TSP_ACK 0x43
#define TSP_EVENT 0x44
#define TSP_LOG 0x45

/* Host -> device types. */
#define TSP_HELLO_REQ 0x01
#define TSP_ARM 0x02
#define TSP_DISARM 0x03
#define TSP_SET_THROTTLE 0x04
#define TSP_IMPULSE 0x05
#define TSP_STOP 0x06
#define TSP_HEARTBEAT 0x07
#define TSP_SET_RATE 0x08
#define TSP_TARE 0x09

/* ACK results. */
enum {
    TSP_OK = 0,
    TSP_BAD_STATE = 1,
    TSP_OUT_OF_RANGE = 2,
    TSP_UNKNOWN_TYPE = 3,
    TSP_BAD_LENGTH = 4,
    TSP_BAD_KEY = 5,
    TSP_BUSY = 6,
    TSP_LIMIT_ACTIVE = 7,
    TSP_VERSION_ERR = 8
};

/* CRC-16/MCRF4XX (poly 0x1021 reflected, init 0xFFFF, no final xor) of `n` bytes, continuing
 * from `crc`. */
uint16_t tsp_crc(uint16_t crc, const uint8_t *p, size_t n);

/* Encodes one frame: body = ver, type, seq (LE), payload, crc (LE), then COBS and the 0x00
 * delimiter into `out` (room for payload_len + 8 bytes). Returns the bytes written, 0 when the
 * payload is too long. */
size_t tsp_encode(uint8_t type, uint16_t seq, const uint8_t *payload, size_t payload_len,
                  uint8_t *out);

/* Decodes the bytes between two delimiters (`n` bytes, no 0x00 inside) in place. On success
 * returns 0 and sets the type, seq, payload pointer (into `buf`) and length. Errors: -1 COBS,
 * -2 too short, -3 CRC, -4 version (type and seq are still set for the VERSION refusal). */
int tsp_decode(uint8_t *buf, size_t n, uint8_t *type, uint16_t *seq, const uint8_t **payload,
               size_t *payload_len);

/* Little-endian stores and loads. */
void tsp_put_u16(uint8_t *p, uint16_t v);
void tsp_put_u32(uint8_t *p, uint32_t v);
void tsp_put_f32(uint8_t *p, float v);
uint16_t tsp_get_u16(const uint8_t *p);
uint32_t tsp_get_u32(const uint8_t *p);

#endif

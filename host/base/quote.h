/* Text from the user (paths, option values, names read from files) inside a
 * one-line message: every control byte escaped, so that a newline cannot
 * split the message and an ESC byte cannot drive the terminal
 * (`-s $'\e[2J'` would clear it). */
#ifndef RTCL_QUOTE_H
#define RTCL_QUOTE_H

#include <stddef.h>

/* Room for the longest escape of one byte ("\x1b") and its NUL. */
#define QUOTE_BYTE_SIZE 5

/* Writes byte c as it appears in a message into out: itself, or \n, \t,
 * \xNN for another control byte or DEL; with quoted, \" and \\ too (text
 * shown between quotes). Returns out. */
const char *quote_byte(unsigned char c, int quoted, char out[QUOTE_BYTE_SIZE]);

/* text with its control bytes escaped (quote_byte, quotes and backslashes
 * left as they are), in one of QUOTE_SLOTS buffers of this thread used in
 * turn: one message may show up to QUOTE_SLOTS texts, each valid until
 * QUOTE_SLOTS more calls in the same thread. A text whose escaped form
 * exceeds QUOTE_TEXT_MAX bytes is cut, ending in "...". NULL gives "". */
#define QUOTE_SLOTS 4
/* The first n bytes of text escaped as quote_text does into out, cut with
 * "..." where the escaped text would pass max bytes (out holds max + 4). */
char *quote_bytes(const char *text, size_t n, char *out, size_t max);

#define QUOTE_TEXT_MAX 4200
const char *quote_text(const char *text);

#endif

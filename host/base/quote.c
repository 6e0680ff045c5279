#include "base/quote.h"

#include <stdio.h>
#include <string.h>

const char *quote_byte(unsigned char c, int quoted, char out[QUOTE_BYTE_SIZE])
{
	if (quoted && (c == '"' || c == '\\'))
		snprintf(out, QUOTE_BYTE_SIZE, "\\%c", c);
	else if (c == '\n')
		snprintf(out, QUOTE_BYTE_SIZE, "\\n");
	else if (c == '\t')
		snprintf(out, QUOTE_BYTE_SIZE, "\\t");
	else if (c < 0x20 || c == 0x7f)
		snprintf(out, QUOTE_BYTE_SIZE, "\\x%02x", c);
	else
		snprintf(out, QUOTE_BYTE_SIZE, "%c", c);
	return out;
}

char *quote_bytes(const char *text, size_t n, char *out, size_t max)
{
	size_t len = 0;

	for (size_t i = 0; i < n; i++) {
		char escaped[QUOTE_BYTE_SIZE];
		size_t e = strlen(quote_byte((unsigned char)text[i], 0, escaped));

		if (len + e > max) {
			while (len > 0 && ((unsigned char)out[len - 1] & 0x80))
				len--; /* no part of a UTF-8 character left */
			memcpy(out + len, "...", 3);
			len += 3;
			break;
		}
		memcpy(out + len, escaped, e);
		len += e;
	}
	out[len] = '\0';
	return out;
}

const char *quote_text(const char *text)
{
	/* Thread-local: the devices' threads build messages at the same time. */
	static _Thread_local char slots[QUOTE_SLOTS][QUOTE_TEXT_MAX + 4];
	static _Thread_local unsigned next;

	text = text ? text : "";
	return quote_bytes(text, strlen(text), slots[next++ % QUOTE_SLOTS], QUOTE_TEXT_MAX);
}

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

const char *quote_text(const char *text)
{
	/* Thread-local: the devices' threads build messages at the same time. */
	static _Thread_local char slots[QUOTE_SLOTS][QUOTE_TEXT_MAX + 4];
	static _Thread_local unsigned next;
	char *out = slots[next++ % QUOTE_SLOTS];
	size_t len = 0;

	for (const char *s = text ? text : ""; *s; s++) {
		char escaped[QUOTE_BYTE_SIZE];
		size_t n = strlen(quote_byte((unsigned char)*s, 0, escaped));

		if (len + n > QUOTE_TEXT_MAX) {
			while (len > 0 && ((unsigned char)out[len - 1] & 0x80))
				len--; /* no part of a UTF-8 character left */
			memcpy(out + len, "...", 3);
			len += 3;
			break;
		}
		memcpy(out + len, escaped, n);
		len += n;
	}
	out[len] = '\0';
	return out;
}

/* Finding the text of a number in the scene file, to name one that jansson
 * read as 0 ("1e-400 underflows"): jansson keeps no text for numbers. */
#include <string.h>

#include "scene/scene_loader.h"

/* The number literals of a document jansson has accepted, in document
 * order: next_number_literal sets *start and *len to the next one and returns
 * 1, or returns 0 at the end. Strings (keys too) are skipped; true, false and
 * null hold no digit or '-', so a number starts at the first '-' or digit. */
struct literal_scan {
	const char *at, *end;
};

static int next_number_literal(struct literal_scan *sc, const char **start, size_t *len)
{
	while (sc->at < sc->end) {
		char c = *sc->at;

		if (c == '"') {
			for (sc->at++; sc->at < sc->end && *sc->at != '"'; sc->at++)
				if (*sc->at == '\\')
					sc->at++;
			sc->at++;
		} else if (c == '-' || (c >= '0' && c <= '9')) {
			*start = sc->at;
			while (sc->at < sc->end && *sc->at && strchr("+-.eE0123456789", *sc->at))
				sc->at++;
			*len = (size_t)(sc->at - *start);
			return 1;
		} else {
			sc->at++;
		}
	}
	return 0;
}

/* Whether a number literal has a nonzero digit before its exponent. */
static int nonzero_as_written(const char *start, size_t len)
{
	for (size_t i = 0; i < len && start[i] != 'e' && start[i] != 'E'; i++)
		if (start[i] >= '1' && start[i] <= '9')
			return 1;
	return 0;
}

/* Walks `v` in document order (jansson keeps the order of object keys),
 * pairing each number with the next literal of the text, until it meets
 * `target`: returns 1 with *start and *len set to its literal, 0 if target is
 * not below v, -1 if the numbers and the literals do not pair up. */
static int find_literal(const json_t *v, const json_t *target, struct literal_scan *sc,
			const char **start, size_t *len)
{
	const char *key;
	json_t *member;
	size_t i;
	int found;

	switch (json_typeof(v)) {
	case JSON_OBJECT:
		json_object_foreach((json_t *)v, key, member)
		{
			found = find_literal(member, target, sc, start, len);
			if (found)
				return found;
		}
		return 0;
	case JSON_ARRAY:
		json_array_foreach(v, i, member)
		{
			found = find_literal(member, target, sc, start, len);
			if (found)
				return found;
		}
		return 0;
	case JSON_INTEGER:
	case JSON_REAL:
		if (!next_number_literal(sc, start, len))
			return -1;
		return v == target;
	default:
		return 0;
	}
}

/* The number `v` as written in the file ("a 400-character number" if too
 * long to quote) if that text is nonzero but jansson read it as 0 or a
 * denormal (1e-400, 1e-320), else NULL. Looked up only for the one number
 * that fails a check, so a scene costs at most one walk. */
const char *loader_underflow_text(const struct loader *ld, const json_t *v,
				  char buf[WRITTEN_NUMBER_MAX])
{
	struct literal_scan sc = {ld->text, ld->text + ld->text_len};
	const char *start;
	size_t len;

	if (!ld->doc || find_literal(ld->doc, v, &sc, &start, &len) != 1 ||
	    !nonzero_as_written(start, len))
		return NULL;
	if (len < WRITTEN_NUMBER_MAX)
		snprintf(buf, WRITTEN_NUMBER_MAX, "%.*s", (int)len, start);
	else
		snprintf(buf, WRITTEN_NUMBER_MAX, "a %zu-character number", len);
	return buf;
}

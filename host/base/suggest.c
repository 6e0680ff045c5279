#include "base/suggest.h"

#include <limits.h>
#include <stdio.h>
#include <string.h>

#include "base/quote.h"

int suggest_distance(const char *a, const char *b)
{
	size_t n = strlen(a), m = strlen(b);
	/* Three rows of the dynamic programme: i-2, i-1 and i. */
	int rows[3][SUGGEST_MAX_LENGTH + 1];

	if (n > SUGGEST_MAX_LENGTH || m > SUGGEST_MAX_LENGTH)
		return INT_MAX;
	for (size_t j = 0; j <= m; j++)
		rows[0][j] = (int)j;
	for (size_t i = 1; i <= n; i++) {
		int *two_up = rows[(i + 1) % 3], *up = rows[(i + 2) % 3], *row = rows[i % 3];
		row[0] = (int)i;
		for (size_t j = 1; j <= m; j++) {
			int cost = a[i - 1] != b[j - 1];
			int best = up[j] + 1; /* deletion */
			if (row[j - 1] + 1 < best)
				best = row[j - 1] + 1; /* insertion */
			if (up[j - 1] + cost < best)
				best = up[j - 1] + cost; /* substitution */
			if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] &&
			    two_up[j - 2] + 1 < best)
				best = two_up[j - 2] + 1; /* swap */
			row[j] = best;
		}
	}
	return rows[n % 3][m];
}

const char *suggest_nearest(const char *word, const char *const *names, size_t count)
{
	int len = (int)strlen(word);
	int limit = len / 3 < 1 ? 1 : len / 3 > 2 ? 2 : len / 3;
	const char *nearest = NULL;
	int best = INT_MAX;

	for (size_t i = 0; i < count; i++) {
		int d = suggest_distance(word, names[i]);
		if (d > 0 && d <= limit && d < best) {
			best = d;
			nearest = names[i];
		}
	}
	return nearest;
}

void suggest_append(char *buf, size_t size, const char *word, const char *const *names,
		    size_t count, const char *prefix)
{
	const char *nearest = suggest_nearest(word, names, count);
	size_t used = strlen(buf);

	if (nearest && used < size)
		snprintf(buf + used, size - used, "; did you mean \"%s%s\"?", prefix,
			 quote_text(nearest)); /* a file's name may hold control bytes */
}

/* ply_check (ply_check.h): a PLY header's declared counts against the body. */
#define _POSIX_C_SOURCE 200809L
#include "meshread/ply_check.h"

#include "scene/mesh.h" /* MESH_MAX_POLYGON_VERTICES */

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MAX_ELEMENTS 32
#define MAX_PROPERTIES 64
#define LINE_MAX_BYTES 4096
#define HEADER_MAX_BYTES (1 << 20) /* host/scene/mesh_spawn.c refuses a longer one */

enum ply_format { ASCII, BINARY_LE, BINARY_BE };

struct property {
	int is_face;	/* a list of vertex indices: a polygon */
	int size;	/* bytes of a scalar, or of a list's items */
	int count_size; /* bytes of a list's length; 0: a scalar */
	int count_signed;
};

struct element {
	char name[64];
	unsigned long long count;
	struct property props[MAX_PROPERTIES];
	int prop_count;
};

struct header {
	enum ply_format format;
	struct element elements[MAX_ELEMENTS];
	int element_count;
	off_t body_start;
};

/* The bytes of a PLY scalar type; 0 for an unknown one. *is_signed: an
 * integer type with a sign; *is_integer: not float or double. */
static int type_size(const char *name, int *is_signed, int *is_integer)
{
	static const struct {
		const char *name;
		int size, is_signed, is_integer;
	} types[] = {
		{"char", 1, 1, 1},  {"uchar", 1, 0, 1},	  {"int8", 1, 1, 1},   {"uint8", 1, 0, 1},
		{"short", 2, 1, 1}, {"ushort", 2, 0, 1},  {"int16", 2, 1, 1},  {"uint16", 2, 0, 1},
		{"int", 4, 1, 1},   {"uint", 4, 0, 1},	  {"int32", 4, 1, 1},  {"uint32", 4, 0, 1},
		{"float", 4, 1, 0}, {"float32", 4, 1, 0}, {"double", 8, 1, 0}, {"float64", 8, 1, 0},
	};

	for (size_t i = 0; i < sizeof(types) / sizeof(types[0]); i++)
		if (strcmp(name, types[i].name) == 0) {
			*is_signed = types[i].is_signed;
			*is_integer = types[i].is_integer;
			return types[i].size;
		}
	return 0;
}

/* One "property ..." line's words into e. Returns 0, or -1 when this check
 * does not understand it. */
static int read_property(struct element *e, char **words, int n)
{
	struct property *p;
	int is_signed, is_integer = 0;

	if (e->prop_count == MAX_PROPERTIES)
		return -1;
	p = &e->props[e->prop_count];
	if (n == 3 && strcmp(words[1], "list") != 0) {
		p->size = type_size(words[1], &is_signed, &is_integer);
		p->count_size = 0;
	} else if (n == 5 && strcmp(words[1], "list") == 0) {
		p->count_size = type_size(words[2], &p->count_signed, &is_integer);
		if (!is_integer)
			return -1;
		p->size = type_size(words[3], &is_signed, &is_integer);
		p->is_face = strcmp(words[4], "vertex_indices") == 0 ||
			     strcmp(words[4], "vertex_index") == 0;
	} else {
		return -1;
	}
	if (p->size == 0 || (words[1][0] == 'l' && p->count_size == 0))
		return -1;
	e->prop_count++;
	return 0;
}

/* Splits line into at most max words (in place). */
static int split(char *line, char **words, int max)
{
	int n = 0;

	for (char *w = strtok(line, " \t\r\n"); w && n < max; w = strtok(NULL, " \t\r\n"))
		words[n++] = w;
	return n;
}

/* Reads the header from f. Returns 1 when it is one this check understands,
 * 0 when not (or not PLY at all), -1 with why in reason when an element line
 * is malformed: Assimp reads a count out of the words it finds there (the mesh
 * fuzzer: "element 4294967295perty list ..." made it allocate 103 GB); or
 * when the header starts again ("ply", or a second "format"). */
static int read_ply_header(FILE *f, struct header *h, char *reason, size_t reason_size)
{
	char line[LINE_MAX_BYTES], *words[8];
	int n, line_number = 1, formats = 0;

	memset(h, 0, sizeof(*h));
	if (!fgets(line, sizeof(line), f) || split(line, words, 8) != 1 ||
	    strcmp(words[0], "ply") != 0)
		return 0;
	while (fgets(line, sizeof(line), f) && ftello(f) <= HEADER_MAX_BYTES) {
		if (!strchr(line, '\n'))
			return 0; /* a line longer than this check reads */
		line_number++;
		n = split(line, words, 8);
		if (n == 0 || strcmp(words[0], "comment") == 0 || strcmp(words[0], "obj_info") == 0)
			continue;
		if (strcmp(words[0], "end_header") == 0) {
			h->body_start = ftello(f);
			return 1;
		}
		/* A header that starts again: Assimp 5.2 aborted, or freed memory
		 * it had not allocated, on these (the mesh fuzzer). */
		if (strcmp(words[0], "ply") == 0) {
			snprintf(reason, reason_size,
				 "line %d of the PLY header: \"ply\" again: a header starts once",
				 line_number);
			return -1;
		}
		if (strcmp(words[0], "format") == 0 && formats++) {
			snprintf(reason, reason_size,
				 "line %d of the PLY header: a second \"format\" line", line_number);
			return -1;
		}
		if (strcmp(words[0], "format") == 0 && n >= 2) {
			if (strcmp(words[1], "ascii") == 0)
				h->format = ASCII;
			else if (strcmp(words[1], "binary_little_endian") == 0)
				h->format = BINARY_LE;
			else if (strcmp(words[1], "binary_big_endian") == 0)
				h->format = BINARY_BE;
			else
				return 0;
		} else if (strcmp(words[0], "element") == 0) {
			struct element *e = &h->elements[h->element_count];
			unsigned long long count = 0;
			char *end = NULL;

			if (n == 3 && words[2][0] >= '0' && words[2][0] <= '9') {
				errno = 0;
				count = strtoull(words[2], &end, 10);
			}
			if (!end || *end || errno) {
				snprintf(reason, reason_size,
					 "line %d of the PLY header: an element line must be "
					 "\"element NAME COUNT\", the count a whole number",
					 line_number);
				return -1;
			}
			if (h->element_count == MAX_ELEMENTS)
				return 0;
			e->count = count;
			snprintf(e->name, sizeof(e->name), "%s", words[1]);
			h->element_count++;
		} else if (strcmp(words[0], "property") == 0) {
			if (h->element_count == 0 ||
			    read_property(&h->elements[h->element_count - 1], words, n))
				return 0;
		} else {
			return 0; /* a line this check does not know */
		}
	}
	return 0;
}

/* The fewest bytes one record of e takes: binary, its scalars and list
 * lengths; ASCII, a character and a separator per value. At least 1, so
 * that a record without properties is not free. */
static unsigned long long min_record_bytes(const struct header *h, const struct element *e)
{
	unsigned long long bytes = 0;

	for (int i = 0; i < e->prop_count; i++) {
		const struct property *p = &e->props[i];
		bytes += h->format == ASCII ? 2
					    : (unsigned)(p->count_size ? p->count_size : p->size);
	}
	return bytes ? bytes : 1;
}

/* Appends "N "name"" for each element to text. */
static void list_counts(const struct header *h, char *text, size_t size)
{
	size_t used = strlen(text);

	for (int i = 0; i < h->element_count && used < size; i++) {
		int n = snprintf(text + used, size - used, "%s%llu \"%s\"",
				 i == 0 ? "" : (i + 1 == h->element_count ? " and " : ", "),
				 h->elements[i].count, h->elements[i].name);
		if (n < 0)
			break;
		used += (size_t)n;
	}
}

/* Whether the declared records can fit the body at all. */
static int fits(const struct header *h, unsigned long long body, char *reason, size_t size)
{
	unsigned long long need = 0, one;
	int overflow = 0;

	for (int i = 0; i < h->element_count; i++) {
		overflow |= __builtin_mul_overflow(h->elements[i].count,
						   min_record_bytes(h, &h->elements[i]), &one);
		overflow |= __builtin_add_overflow(need, one, &need);
	}
	if (h->format == ASCII && need > 0)
		need--; /* the last value needs no separator after it */
	if (!overflow && need <= body)
		return 1;
	snprintf(reason, size, "its PLY header declares ");
	list_counts(h, reason, size);
	size_t used = strlen(reason);
	if (used < size) {
		if (overflow)
			snprintf(reason + used, size - used,
				 " records, more bytes than a file can hold; the file holds %llu "
				 "after its header",
				 body);
		else
			snprintf(reason + used, size - used,
				 " records, at least %llu bytes, but the file holds %llu after its "
				 "header",
				 need, body);
	}
	return 0;
}

/* The body, read in blocks. */
struct body {
	int fd;
	unsigned char buf[1 << 16];
	size_t pos, len;
};

/* Makes at least one byte available; 0 at the end of the file. */
static int refill_body(struct body *b)
{
	ssize_t n;

	if (b->pos < b->len)
		return 1;
	do
		n = read(b->fd, b->buf, sizeof(b->buf));
	while (n < 0 && errno == EINTR);
	if (n <= 0)
		return 0;
	b->pos = 0;
	b->len = (size_t)n;
	return 1;
}

/* Skips n bytes; 0 when the file ends first. */
static int skip(struct body *b, unsigned long long n)
{
	while (n > 0) {
		if (!refill_body(b))
			return 0;
		size_t take = b->len - b->pos < n ? b->len - b->pos : (size_t)n;
		b->pos += take;
		n -= take;
	}
	return 1;
}

/* A binary list length of `size` bytes; -1 when the file ends first or the
 * length is negative. */
static long long read_count(struct body *b, const struct header *h, const struct property *p)
{
	unsigned char bytes[4];
	unsigned long long value = 0;

	for (int i = 0; i < p->count_size; i++) {
		if (!refill_body(b))
			return -1;
		bytes[i] = b->buf[b->pos++];
	}
	for (int i = 0; i < p->count_size; i++) {
		int k = h->format == BINARY_LE ? p->count_size - 1 - i : i;
		value = value << 8 | bytes[k];
	}
	if (p->count_signed && (value >> (8 * p->count_size - 1)) & 1)
		return -1;
	return (long long)value;
}

/* The next whitespace-separated word of an ASCII body into word (cut to
 * size - 1 characters); 0 at the end of the file. */
static int next_word(struct body *b, char *word, size_t size)
{
	size_t n = 0;

	for (;;) {
		if (!refill_body(b))
			return 0;
		unsigned char c = b->buf[b->pos];
		if (c != ' ' && c != '\t' && c != '\r' && c != '\n')
			break;
		b->pos++;
	}
	while (refill_body(b)) {
		unsigned char c = b->buf[b->pos];
		if (c == ' ' || c == '\t' || c == '\r' || c == '\n')
			break;
		if (n + 1 < size)
			word[n++] = (char)c;
		b->pos++;
	}
	word[n] = '\0';
	return 1;
}

/* One record of e; 0 when the body ends inside it, -1 for a list length that
 * is not a whole number (ASCII) or is negative (binary), -2 for a polygon of
 * more than MESH_MAX_POLYGON_VERTICES. */
static int read_record(struct body *b, const struct header *h, const struct element *e)
{
	char word[32];

	for (int i = 0; i < e->prop_count; i++) {
		const struct property *p = &e->props[i];
		unsigned long long items = 0;

		if (h->format == ASCII) {
			char *end;
			if (!next_word(b, word, sizeof(word)))
				return 0;
			if (!p->count_size)
				continue;
			if (word[0] < '0' || word[0] > '9')
				return -1;
			items = strtoull(word, &end, 10);
			if (*end)
				return -1;
			if (p->is_face && items > MESH_MAX_POLYGON_VERTICES)
				return -2;
			for (unsigned long long k = 0; k < items; k++)
				if (!next_word(b, word, sizeof(word)))
					return 0;
			continue;
		}
		if (p->count_size) {
			long long count = read_count(b, h, p);
			if (count < 0)
				return b->pos < b->len || refill_body(b) ? -1 : 0;
			items = (unsigned long long)count;
			if (p->is_face && items > MESH_MAX_POLYGON_VERTICES)
				return -2;
		} else {
			items = 1;
		}
		if (!skip(b, items * (unsigned)p->size))
			return 0;
	}
	return 1;
}

/* Whether the body holds every declared record. */
static int body_whole(struct body *b, const struct header *h, char *reason, size_t size)
{
	for (int i = 0; i < h->element_count; i++) {
		const struct element *e = &h->elements[i];
		int scalars_only = 1;

		for (int k = 0; k < e->prop_count; k++)
			scalars_only &= e->props[k].count_size == 0;
		if (e->prop_count == 0)
			continue;
		if (scalars_only && h->format != ASCII) {
			if (skip(b, e->count * min_record_bytes(h, e)))
				continue;
			snprintf(reason, size,
				 "its PLY header declares %llu \"%s\" records, but the file ends "
				 "before their end (a truncated file, or a header that does not "
				 "match it)",
				 e->count, e->name);
			return 0;
		}
		for (unsigned long long r = 0; r < e->count; r++) {
			int got = read_record(b, h, e);
			if (got == 1)
				continue;
			if (got == -2)
				snprintf(reason, size,
					 "its PLY \"%s\" record %llu is a polygon of more than the "
					 "%d vertices a polygon may have",
					 e->name, r, MESH_MAX_POLYGON_VERTICES);
			else if (got < 0)
				snprintf(reason, size,
					 "its PLY \"%s\" record %llu has a list length that is not "
					 "a "
					 "whole number",
					 e->name, r);
			else
				snprintf(
					reason, size,
					"its PLY header declares %llu \"%s\" records, but the file "
					"ends after %llu of them (a truncated file, or a header "
					"that "
					"does not match it)",
					e->count, e->name, r);
			return 0;
		}
	}
	return 1;
}

int ply_check(const char *path, char *reason, size_t reason_size)
{
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC), header_fd = -1;
	struct body *b = NULL;
	struct header *h = NULL;
	struct stat st;
	FILE *f = NULL;
	int ret = 0;

	if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode))
		goto out_close; /* the importer says why */
	h = malloc(sizeof(*h));
	b = malloc(sizeof(*b));
	header_fd = dup(fd);
	f = header_fd >= 0 ? fdopen(header_fd, "rb") : NULL;
	if (!f && header_fd >= 0)
		close(header_fd);
	int header = h && b && f ? read_ply_header(f, h, reason, reason_size) : 0;
	if (header <= 0) {
		ret = header;
		goto out_close;
	}
	if (!fits(h, (unsigned long long)(st.st_size - h->body_start), reason, reason_size)) {
		ret = -1;
		goto out_close;
	}
	b->fd = fd;
	b->pos = b->len = 0;
	if (lseek(fd, h->body_start, SEEK_SET) != h->body_start)
		goto out_close;
	if (!body_whole(b, h, reason, reason_size))
		ret = -1;
out_close:
	if (f)
		fclose(f);
	free(b);
	free(h);
	if (fd >= 0)
		close(fd);
	return ret;
}

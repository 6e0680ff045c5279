/* MTL texture options (mtl_read.h). */
#define _POSIX_C_SOURCE 200809L
#include "meshread/mtl_read.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Whether word is a whole number (strtod takes all of it). */
static int number(const char *word, double *out)
{
	char *end;

	*out = strtod(word, &end);
	return end != word && *end == '\0';
}

/* The -s and -o of one map_Kd or map_d statement (its words after the
 * keyword) into t; returns whether it gives either. Each takes one to three
 * numbers (u, then v and w, which default as the MTL specification says:
 * scale 1, offset 0); the other options and the file name are passed over. */
static int read_options(char *words, struct mtl_transform *t)
{
	int given = 0;
	char *save = NULL;

	t->scale[0] = t->scale[1] = 1;
	t->offset[0] = t->offset[1] = 0;
	for (char *w = strtok_r(words, " \t", &save); w;) {
		int scale = strcmp(w, "-s") == 0, offset = strcmp(w, "-o") == 0;
		double value;

		w = strtok_r(NULL, " \t", &save);
		if (!scale && !offset)
			continue;
		for (int k = 0; k < 3 && w && number(w, &value); k++) {
			if (k < 2)
				(scale ? t->scale : t->offset)[k] = value;
			w = strtok_r(NULL, " \t", &save);
		}
		given = 1;
	}
	return given;
}

int mtl_read_transforms(const char *path, struct mtl_transform **list, size_t *count)
{
	char material[MESH_NAME_MAX] = "", *line = NULL;
	size_t capacity = 0;
	struct stat st;
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC), ret = 0;
	FILE *f;

	if (fd < 0)
		return 0;
	if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || !(f = fdopen(fd, "r"))) {
		close(fd);
		return 0;
	}
	while (getline(&line, &capacity, f) >= 0) {
		char *p = line + strspn(line, " \t");
		size_t n = strlen(p);
		struct mtl_transform t;

		while (n > 0 && strchr(" \t\r\n", p[n - 1]))
			p[--n] = '\0';
		if (strncmp(p, "newmtl", 6) == 0 && (p[6] == ' ' || p[6] == '\t')) {
			/* Assimp 5.2: the rest of the line, blanks trimmed. */
			snprintf(material, sizeof(material), "%s", p + 7 + strspn(p + 7, " \t"));
			continue;
		}
		int kd = strncmp(p, "map_Kd", 6) == 0 && (p[6] == ' ' || p[6] == '\t');
		int d = strncmp(p, "map_d", 5) == 0 && (p[5] == ' ' || p[5] == '\t');
		if (!(kd || d) || !read_options(p + (kd ? 6 : 5), &t))
			continue;
		struct mtl_transform *grown = realloc(*list, (*count + 1) * sizeof(*grown));
		if (!grown) {
			ret = -1;
			break;
		}
		memcpy(t.material, material, sizeof(material));
		t.role = kd ? MESH_TEXTURE_COLOR : MESH_TEXTURE_OPACITY;
		*list = grown;
		(*list)[(*count)++] = t;
	}
	free(line);
	fclose(f);
	return ret;
}

/* mesh_import (mesh.h): the mesh import helper, rtcl-meshread, started for
 * each mesh file with posix_spawn, answers through a pipe: a header, then
 * the arrays as they are. A helper that dies (Assimp's abort() on a malformed
 * file) or answers nonsense costs a message, never rtcl.
 *
 * posix_spawn, not fork: rtcl has threads by the time it loads a scene (the
 * one that takes signals, interrupt.h), and a forked child of a threaded
 * process may deadlock on a lock another thread held (a fork-based version
 * hung once under AddressSanitizer); a spawned program starts afresh. */
#define _GNU_SOURCE /* strsignal */
#include "scene/mesh.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <limits.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "base/libdir.h"

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

extern char **environ;

/* The header of the helper's answer: the import's outcome and the arrays'
 * sizes, then (ok) the arrays (positions, normals, indices, the triangles'
 * materials, the materials) or (!ok) reason_length bytes of reason. */
struct reply {
	uint32_t magic, ok, has_normals, reason_length;
	uint64_t vertex_count, triangle_count, material_count;
	uint32_t has_uvs, layout; /* reply_layout() of the helper's build */
	uint64_t texture_count, texel_bytes; /* then the uvs, textures and texels */
	uint64_t camera_count;		     /* then the cameras */
	uint64_t light_count;		     /* then the lights */
	uint64_t file_count;		     /* then the textures' names, then the files read */
};
#define REPLY_MAGIC 0x6873656du /* "mesh" */
/* The form of the answer: raise it whenever what crosses the pipe changes in a
 * way the sizes below do not show, so that a helper of another rtcl (an old
 * rtcl-meshread named in RTCL_MESHREAD, say) is told apart from a broken one. */
#define REPLY_FORM 3u

/* The form of the answer and the sizes of what crosses the pipe, which an
 * answer carries so that rtcl reads only a helper built beside it. */
static uint32_t reply_layout(void)
{
	return REPLY_FORM << 24 ^
	       (uint32_t)(sizeof(struct reply) + 7u * sizeof(struct mesh_material) +
			  31u * sizeof(struct mesh_texture) + 127u * sizeof(struct mesh_camera) +
			  1023u * sizeof(struct mesh_light));
}

/* The part of the header read before the rest: through the layout, where
 * every form of the answer has had it. */
#define REPLY_HEAD offsetof(struct reply, texture_count)
#define REASON_MAX 1024
/* The longest name or path that crosses the pipe: a path of PATH_MAX, or a
 * name Assimp keeps (1023 bytes), with room to spare. */
#define TEXT_MAX 65536

static int write_all(int fd, const void *data, size_t size)
{
	const char *p = data;

	while (size > 0) {
		ssize_t n = write(fd, p, size);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return -1;
		p += n;
		size -= (size_t)n;
	}
	return 0;
}

/* When the helper's answer must be in: CLOCK_MONOTONIC seconds, or 0 for
 * no limit. */
static double deadline;

static double now(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return (double)t.tv_sec + t.tv_nsec * 1e-9;
}

/* Outcomes of read_all besides 0. */
#define ENDED (-1)    /* the pipe ended or failed */
#define TOO_LATE (-2) /* the deadline passed */

/* Reads size bytes from fd, waiting no later than the deadline. */
static int read_all(int fd, void *data, size_t size)
{
	char *p = data;

	while (size > 0) {
		if (deadline > 0) {
			double left = deadline - now();
			struct pollfd pfd = {.fd = fd, .events = POLLIN};
			int ready;

			if (left <= 0)
				return TOO_LATE;
			ready = poll(&pfd, 1, left > 1e6 ? 1000000000 : (int)(left * 1000) + 1);
			if (ready < 0 && errno == EINTR)
				continue;
			if (ready == 0)
				continue; /* the loop sees whether the deadline passed */
			if (ready < 0)
				return ENDED;
		}
		ssize_t n = read(fd, p, size);
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return ENDED;
		p += n;
		size -= (size_t)n;
	}
	return 0;
}

/* A string on the pipe: its length (32 bits), then its bytes. */
static int write_text(int fd, const char *text)
{
	size_t n = strlen(text);
	uint32_t length = n < TEXT_MAX ? (uint32_t)n : TEXT_MAX;

	return write_all(fd, &length, sizeof(length)) || write_all(fd, text, length) ? -1 : 0;
}

/* The names of the textures, then the files read (each its kind, then its path). */
static int write_names(int fd, const struct mesh_data *mesh)
{
	for (size_t i = 0; i < mesh->texture_count; i++)
		if (write_text(fd, mesh->textures[i].name ? mesh->textures[i].name : ""))
			return -1;
	for (size_t i = 0; i < mesh->file_count; i++)
		if (write_all(fd, &mesh->files[i].kind, sizeof(mesh->files[i].kind)) ||
		    write_text(fd, mesh->files[i].path))
			return -1;
	return 0;
}

int mesh_send(int fd, const struct mesh_data *mesh, const char *reason)
{
	struct reply r = {.magic = REPLY_MAGIC, .layout = reply_layout()};

	if (!mesh) {
		size_t n = strlen(reason);
		r.reason_length = n < REASON_MAX ? (uint32_t)n : REASON_MAX;
		return write_all(fd, &r, sizeof(r)) || write_all(fd, reason, r.reason_length) ? -1
											      : 0;
	}
	r.ok = 1;
	r.has_normals = mesh->normals != NULL;
	r.vertex_count = mesh->vertex_count;
	r.triangle_count = mesh->triangle_count;
	r.material_count = mesh->material_count;
	r.has_uvs = mesh->uvs != NULL;
	r.texture_count = mesh->texture_count;
	r.texel_bytes = mesh->texel_bytes;
	r.camera_count = mesh->camera_count;
	r.file_count = mesh->file_count;
	r.light_count = mesh->light_count;
	if (write_all(fd, &r, sizeof(r)) ||
	    write_all(fd, mesh->positions, 3 * mesh->vertex_count * sizeof(double)) ||
	    (mesh->normals &&
	     write_all(fd, mesh->normals, 3 * mesh->vertex_count * sizeof(double))) ||
	    write_all(fd, mesh->indices, 3 * mesh->triangle_count * sizeof(size_t)) ||
	    write_all(fd, mesh->triangle_materials, mesh->triangle_count * sizeof(uint32_t)) ||
	    write_all(fd, mesh->materials, mesh->material_count * sizeof(struct mesh_material)) ||
	    (mesh->uvs && write_all(fd, mesh->uvs, 2 * mesh->vertex_count * sizeof(double))) ||
	    write_all(fd, mesh->textures, mesh->texture_count * sizeof(struct mesh_texture)) ||
	    write_all(fd, mesh->texels, mesh->texel_bytes) ||
	    write_all(fd, mesh->cameras, mesh->camera_count * sizeof(struct mesh_camera)) ||
	    write_all(fd, mesh->lights, mesh->light_count * sizeof(struct mesh_light)) ||
	    write_names(fd, mesh))
		return -1;
	return 0;
}

void mesh_data_free(struct mesh_data *mesh)
{
	free(mesh->positions);
	free(mesh->normals);
	free(mesh->indices);
	free(mesh->triangle_materials);
	free(mesh->materials);
	free(mesh->uvs);
	for (size_t i = 0; mesh->textures && i < mesh->texture_count; i++)
		free(mesh->textures[i].name);
	free(mesh->textures);
	for (size_t i = 0; mesh->files && i < mesh->file_count; i++)
		free(mesh->files[i].path);
	free(mesh->files);
	free(mesh->texels);
	free(mesh->cameras);
	free(mesh->lights);
	memset(mesh, 0, sizeof(*mesh));
}

/* Outcomes of receive() besides 0 and MESH_REFUSED. */
#define BROKE_OFF (-10)	    /* the pipe ended early: the helper died */
#define NONSENSE (-11)	    /* an answer no helper of this rtcl sends */
#define OUT_OF_MEMORY (-12) /* reason says for what */
#define TIMED_OUT (-13)	    /* no answer within the time limit */
#define OTHER_FORM (-14)    /* an answer of another rtcl's helper */

/* An array of count items of item_size bytes: NULL for an impossible size
 * (counts from the pipe are not trusted). */
static void *alloc_array(uint64_t count, size_t item_size)
{
	if (count > SIZE_MAX / item_size)
		return NULL;
	return malloc(count ? (size_t)count * item_size : 1);
}

/* A string written by write_text into *text (malloc'd, NUL-terminated). */
static int read_text(int fd, char **text)
{
	uint32_t length;
	int got = read_all(fd, &length, sizeof(length));

	if (got)
		return got;
	if (length > TEXT_MAX)
		return NONSENSE;
	*text = malloc((size_t)length + 1);
	if (!*text)
		return OUT_OF_MEMORY;
	(*text)[length] = '\0';
	got = read_all(fd, *text, length);
	/* A NUL inside would cut the name short, as names were cut before. */
	return got ? got : strlen(*text) != length ? NONSENSE : 0;
}

/* The textures' names and the files read, after the arrays. */
static int read_names(int fd, struct mesh_data *out)
{
	int got = 0;

	for (size_t i = 0; !got && i < out->texture_count; i++)
		got = read_text(fd, &out->textures[i].name);
	for (size_t i = 0; !got && i < out->file_count; i++) {
		got = read_all(fd, &out->files[i].kind, sizeof(out->files[i].kind));
		if (!got)
			got = read_text(fd, &out->files[i].path);
		if (!got && out->files[i].kind > MESH_FILE_OTHER)
			got = NONSENSE;
	}
	return got;
}

/* The answer on fd, into *out (ok) or reason (refused). */
static int receive(int fd, struct mesh_data *out, char *reason, size_t reason_size)
{
	struct reply r;

	int got = read_all(fd, &r, REPLY_HEAD);

	if (got)
		return got == TOO_LATE ? TIMED_OUT : BROKE_OFF;
	if (r.magic != REPLY_MAGIC)
		return NONSENSE;
	if (r.layout != reply_layout())
		return OTHER_FORM;
	got = read_all(fd, (char *)&r + REPLY_HEAD, sizeof(r) - REPLY_HEAD);
	if (got)
		return got == TOO_LATE ? TIMED_OUT : BROKE_OFF;
	if (!r.ok) {
		char text[REASON_MAX + 1];
		if (r.reason_length > REASON_MAX)
			return NONSENSE;
		got = read_all(fd, text, r.reason_length);
		if (got)
			return got == TOO_LATE ? TIMED_OUT : BROKE_OFF;
		text[r.reason_length] = '\0';
		snprintf(reason, reason_size, "%s", text);
		return MESH_REFUSED;
	}
	out->positions = alloc_array(r.vertex_count, 3 * sizeof(double));
	out->normals = r.has_normals ? alloc_array(r.vertex_count, 3 * sizeof(double)) : NULL;
	out->indices = alloc_array(r.triangle_count, 3 * sizeof(size_t));
	out->triangle_materials = alloc_array(r.triangle_count, sizeof(uint32_t));
	out->materials = alloc_array(r.material_count, sizeof(struct mesh_material));
	out->uvs = r.has_uvs ? alloc_array(r.vertex_count, 2 * sizeof(double)) : NULL;
	out->textures = alloc_array(r.texture_count, sizeof(struct mesh_texture));
	out->texels = alloc_array(r.texel_bytes, 1);
	out->cameras = alloc_array(r.camera_count, sizeof(struct mesh_camera));
	out->files = alloc_array(r.file_count, sizeof(struct mesh_file));
	out->lights = alloc_array(r.light_count, sizeof(struct mesh_light));
	if (!out->cameras || !out->files || !out->lights || !out->positions || (r.has_normals && !out->normals) ||
	    !out->indices || !out->triangle_materials || !out->materials ||
	    (r.has_uvs && !out->uvs) || !out->textures || !out->texels) {
		snprintf(reason, reason_size, "out of memory for %llu triangles",
			 (unsigned long long)r.triangle_count);
		return OUT_OF_MEMORY;
	}
	out->vertex_count = (size_t)r.vertex_count;
	out->triangle_count = (size_t)r.triangle_count;
	out->material_count = (size_t)r.material_count;
	out->texture_count = (size_t)r.texture_count;
	out->texel_bytes = (size_t)r.texel_bytes;
	out->camera_count = (size_t)r.camera_count;
	out->light_count = (size_t)r.light_count;
	out->file_count = (size_t)r.file_count;
	/* Nothing for mesh_data_free to free before it is read. */
	memset(out->textures, 0, out->texture_count * sizeof(struct mesh_texture));
	memset(out->files, 0, out->file_count * sizeof(struct mesh_file));
	got = read_all(fd, out->positions, 3 * out->vertex_count * sizeof(double));
	if (!got && r.has_normals)
		got = read_all(fd, out->normals, 3 * out->vertex_count * sizeof(double));
	if (!got)
		got = read_all(fd, out->indices, 3 * out->triangle_count * sizeof(size_t));
	if (!got)
		got = read_all(fd, out->triangle_materials, out->triangle_count * sizeof(uint32_t));
	if (!got)
		got = read_all(fd, out->materials,
			       out->material_count * sizeof(struct mesh_material));
	if (!got && r.has_uvs)
		got = read_all(fd, out->uvs, 2 * out->vertex_count * sizeof(double));
	if (!got) {
		got = read_all(fd, out->textures, out->texture_count * sizeof(struct mesh_texture));
		for (size_t i = 0; i < out->texture_count; i++)
			out->textures[i].name = NULL; /* the helper's pointers: read below */
	}
	if (!got)
		got = read_all(fd, out->texels, out->texel_bytes);
	if (!got)
		got = read_all(fd, out->cameras, out->camera_count * sizeof(struct mesh_camera));
	if (!got)
		got = read_all(fd, out->lights, out->light_count * sizeof(struct mesh_light));
	if (!got)
		got = read_names(fd, out);
	if (got == NONSENSE || got == OUT_OF_MEMORY) {
		if (got == OUT_OF_MEMORY)
			snprintf(reason, reason_size, "out of memory for its names");
		return got;
	}
	if (got)
		return got == TOO_LATE ? TIMED_OUT : BROKE_OFF;
	for (size_t i = 0; i < 3 * out->triangle_count; i++)
		if (out->indices[i] >= out->vertex_count)
			return NONSENSE;
	for (size_t i = 0; i < out->triangle_count; i++)
		if (out->triangle_materials[i] != MESH_NO_MATERIAL &&
		    out->triangle_materials[i] >= out->material_count)
			return NONSENSE;
	for (size_t i = 0; i < out->material_count; i++) {
		struct mesh_material *m = &out->materials[i];
		m->name[MESH_NAME_MAX - 1] = m->not_understood[MESH_NOTES_MAX - 1] = '\0';
		if (m->kind > MESH_MATERIAL_METALLIC_ROUGHNESS || m->alpha_mode > MESH_ALPHA_MASK ||
		    m->base_texture < -1 || m->base_texture >= (int64_t)out->texture_count ||
		    m->opacity_texture < -1 || m->opacity_texture >= (int64_t)out->texture_count)
			return NONSENSE;
	}
	for (size_t i = 0; i < out->texture_count; i++) {
		struct mesh_texture *t = &out->textures[i];
		uint64_t texel_size = t->format == MESH_TEXELS_FLOAT ? 16 : 4;
		t->reason[MESH_TEXTURE_REASON_MAX - 1] = '\0';
		if (t->reason[0])
			continue;
		if (t->format > MESH_TEXELS_FLOAT || t->role > MESH_TEXTURE_DATA ||
		    t->wrap_s > MESH_WRAP_MIRROR || t->wrap_t > MESH_WRAP_MIRROR || t->width == 0 ||
		    t->height == 0 || t->width > MESH_TEXTURE_MAX_SIDE ||
		    t->height > MESH_TEXTURE_MAX_SIDE ||
		    t->bytes != (uint64_t)t->width * t->height * texel_size ||
		    t->offset > out->texel_bytes || t->bytes > out->texel_bytes - t->offset)
			return NONSENSE;
	}
	/* The numbers are the file's: the scene loader checks them. */
	for (size_t i = 0; i < out->camera_count; i++) {
		out->cameras[i].name[MESH_NAME_MAX - 1] = '\0';
		if (out->cameras[i].kind > MESH_CAMERA_NOT_GLTF)
			return NONSENSE;
	}
	for (size_t i = 0; i < out->light_count; i++) {
		out->lights[i].name[MESH_NAME_MAX - 1] = '\0';
		if (out->lights[i].kind > MESH_LIGHT_OTHER)
			return NONSENSE;
	}
	return 0;
}

/* The line of the helper's stderr (captured in f) that says most: the first
 * that is not blank, a rule of '=' (a sanitizer report opens with one) or
 * AddressSanitizer's line that a signal came before its report.
 * "" when it said nothing. */
static void helper_said(FILE *f, char *line, size_t size)
{
	line[0] = '\0';
	if (!f || fseek(f, 0, SEEK_SET))
		return;
	while (fgets(line, (int)size, f)) {
		line[strcspn(line, "\r\n")] = '\0';
		if (line[strspn(line, " \t=")] != '\0' && !strstr(line, "Sanitizer:DEADLYSIGNAL"))
			return;
	}
	line[0] = '\0';
}

/* Whether the helper's words come from a sanitizer (a test build's check
 * that failed, in rtcl's code unless sanitizer_blames_assimp). */
static int sanitizer_report(const char *said)
{
	return strstr(said, "Sanitizer") || strstr(said, "runtime error:");
}

/* Whether a sanitizer report (captured in f) puts the fault inside Assimp:
 * its first stack frame in code that is not the sanitizer's own is in
 * libassimp, not in rtcl's sources (host/...c, symbolized from the test
 * build's debug information). Frames of the sanitizer runtime name only
 * the helper binary. A SEGV or a bad free in Assimp is the file's fault,
 * as the plain helper's crash is; a report in rtcl's code, or one without
 * frames (UBSan's), is not. */
static int sanitizer_blames_assimp(FILE *f)
{
	char line[1024];

	if (!f || fseek(f, 0, SEEK_SET))
		return 0;
	while (fgets(line, (int)sizeof(line), f)) {
		const char *p = line + strspn(line, " \t");
		if (p[0] != '#' || p[1] < '0' || p[1] > '9')
			continue;
		if (strstr(p, "libassimp"))
			return 1;
		if (strstr(p, "/host/") && strstr(p, ".c:"))
			return 0;
	}
	return 0;
}

/* Whether a sanitizer report (captured in f) says an allocation failed: more
 * memory than there is, or than the sanitizer allocates at once. The file
 * asked for it (a count of 2^32 - 1, say), as when the plain helper's
 * allocation fails under the memory limit; the report's stack may stop at
 * operator new in libstdc++, so it cannot say whose code asked. */
static int sanitizer_out_of_memory(FILE *f)
{
	char line[1024];

	if (!f || fseek(f, 0, SEEK_SET))
		return 0;
	while (fgets(line, (int)sizeof(line), f))
		if (strstr(line, "Sanitizer") &&
		    (strstr(line, "allocator is out of memory") ||
		     strstr(line, "allocation-size-too-big") || strstr(line, "out-of-memory")))
			return 1;
	return 0;
}

/* Waits for the helper, then turns what happened into the outcome: the
 * answer received, or why there is none. */
static int reap(const char *helper, pid_t pid, int received, FILE *said_file, char *reason,
		size_t reason_size)
{
	char said[400], paren[420] = "";
	int status, code;

	while (waitpid(pid, &status, 0) < 0)
		if (errno != EINTR) {
			snprintf(reason, reason_size,
				 "the mesh importer failed: waiting for it: %s", strerror(errno));
			return MESH_IMPORTER_FAILED;
		}
	helper_said(said_file, said, sizeof(said));
	if (said[0])
		snprintf(paren, sizeof(paren), ": %s", said);
	code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
	/* Answers cut short here end the helper with SIGPIPE: not its fault. */
	if (received == OUT_OF_MEMORY)
		return MESH_REFUSED;
	if (received == TIMED_OUT) {
		snprintf(reason, reason_size,
			 "the import took longer than its limit of %lu s (--mesh-time-limit "
			 "or " MESH_TIME_LIMIT_ENV ")",
			 mesh_get_limits().seconds);
		return MESH_REFUSED;
	}
	/* An allocation that failed under the memory limit where Assimp does
	 * not catch it: "terminate called after throwing ... std::bad_alloc". */
	if (WIFSIGNALED(status) && mesh_get_limits().memory_mib &&
	    (strstr(said, "bad_alloc") || strstr(said, MESH_MEMORY_NOTE))) {
		snprintf(reason, reason_size, MESH_MEMORY_MESSAGE, mesh_get_limits().memory_mib);
		return MESH_REFUSED;
	}
	if (received == NONSENSE) {
		snprintf(reason, reason_size,
			 "the mesh importer failed: its answer makes no sense");
		return MESH_IMPORTER_FAILED;
	}
	if (received == OTHER_FORM) {
		snprintf(reason, reason_size,
			 "the mesh importer %s is another rtcl's (its answer has another "
			 "form): name the rtcl-meshread built with this rtcl in " MESH_HELPER_ENV
			 ", or reinstall rtcl",
			 helper);
		return MESH_IMPORTER_FAILED;
	}
	/* A sanitized helper (test builds) ends with exit status 1, or a
	 * signal, after its report. */
	if ((WIFSIGNALED(status) || code != 0) && sanitizer_report(said)) {
		if (sanitizer_out_of_memory(said_file)) {
			if (mesh_get_limits().memory_mib)
				snprintf(reason, reason_size, MESH_MEMORY_MESSAGE,
					 mesh_get_limits().memory_mib);
			else
				snprintf(reason, reason_size,
					 "the import needed more memory than there is");
			return MESH_REFUSED;
		}
		if (sanitizer_blames_assimp(said_file)) {
			snprintf(reason, reason_size,
				 "the importer (Assimp) crashed on it%s; the file is malformed",
				 paren);
			return MESH_REFUSED;
		}
		snprintf(reason, reason_size, "the mesh importer failed%s", paren);
		return MESH_IMPORTER_FAILED;
	}
	if (WIFSIGNALED(status)) {
		int sig = WTERMSIG(status);
		if (sig == SIGINT || sig == SIGTERM || sig == SIGHUP || sig == SIGKILL) {
			snprintf(reason, reason_size,
				 "the mesh importer was stopped by a signal (%s)", strsignal(sig));
			return MESH_REFUSED;
		}
		snprintf(reason, reason_size,
			 "the importer (Assimp) crashed on it (%s%s); the file is malformed",
			 strsignal(sig), paren);
		return MESH_REFUSED;
	}
	if (code != 0) {
		snprintf(reason, reason_size, "the mesh importer failed (exit status %d)%s", code,
			 paren);
		return MESH_IMPORTER_FAILED;
	}
	if (received == BROKE_OFF) {
		snprintf(reason, reason_size,
			 "the mesh importer failed: it ended without an answer");
		return MESH_IMPORTER_FAILED;
	}
	return received;
}

static int has_ply_extension(const char *path)
{
	size_t n = strlen(path);

	return n >= 4 && strcasecmp(path + n - 4, ".ply") == 0;
}

/* How much of a PLY file is searched for the end of its header. */
#define PLY_HEADER_MAX (1 << 20)

/* Whether the file at path, open at its start in f, is a PLY file (named
 * .ply and starting "ply", or whose first line is "ply") whose header does
 * not end in a line "end_header" (trailing blanks allowed) within its first
 * PLY_HEADER_MAX bytes: Assimp 5.2's PLY reader loops forever on one (found
 * by test/fuzz_mesh.c), so such a file is refused before it. */
static int ply_header_unterminated(const char *path, FILE *f)
{
	char magic[4], *line = NULL;
	size_t capacity = 0, got = fread(magic, 1, sizeof(magic), f), read = 0;
	int magic_line = got == 4 && (magic[3] == '\n' || magic[3] == '\r');
	int unterminated = 0;
	ssize_t n;

	if (got < 3 || memcmp(magic, "ply", 3) != 0 || !(magic_line || has_ply_extension(path)))
		return 0;
	unterminated = 1;
	rewind(f);
	while (read < PLY_HEADER_MAX && (n = getline(&line, &capacity, f)) >= 0) {
		read += (size_t)n;
		if (strncmp(line, "end_header", 10) == 0 &&
		    strspn(line + 10, " \t\r\n") == strlen(line + 10)) {
			unterminated = 0;
			break;
		}
	}
	free(line);
	return unterminated;
}

/* What the importer would say vaguely, not at all, or never: a missing file,
 * a folder, a FIFO or device (opened without blocking, then refused), a PLY
 * header without its end. 0 when the file may go to Assimp. */
static int probe_file(const char *path, char *reason, size_t reason_size)
{
	struct stat st;
	int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
	FILE *probe;

	if (fd < 0) {
		snprintf(reason, reason_size, "%s", strerror(errno));
		return -1;
	}
	if (fstat(fd, &st) != 0) {
		snprintf(reason, reason_size, "%s", strerror(errno));
		close(fd);
		return -1;
	}
	if (!S_ISREG(st.st_mode)) {
		snprintf(reason, reason_size, "%s",
			 S_ISDIR(st.st_mode) ? strerror(EISDIR) : "not a regular file");
		close(fd);
		return -1;
	}
	probe = fdopen(fd, "rb");
	if (!probe) {
		snprintf(reason, reason_size, "%s", strerror(errno));
		close(fd);
		return -1;
	}
	if (ply_header_unterminated(path, probe)) {
		fclose(probe);
		snprintf(reason, reason_size,
			 "its PLY header has no end_header line (a truncated or broken file)");
		return -1;
	}
	fclose(probe);
	return 0;
}

/* The helper program: $RTCL_MESHREAD, else the installed or built one. */
static int helper_path(char *path, size_t size)
{
	const char *named = getenv(MESH_HELPER_ENV);

	if (named && named[0]) {
		snprintf(path, size, "%s", named);
		return 0;
	}
	return libdir_find(MESH_HELPER_NAME, path, size);
}

/* Starts the helper on path with its stdout on answer_fd and its stderr in
 * said (or /dev/null). The signals rtcl blocks in every thread (interrupt.h)
 * are unblocked and at their defaults in the helper, so Ctrl-C stops it too. */
static int start_helper(const char *helper, const char *path, int answer_fd, FILE *said, pid_t *pid,
			char *reason, size_t reason_size)
{
	posix_spawn_file_actions_t actions;
	posix_spawnattr_t attr;
	sigset_t none, defaults;
	char memory[32];
	char *argv[] = {(char *)MESH_HELPER_NAME, "--memory-limit", memory, (char *)path, NULL};
	int err;

	snprintf(memory, sizeof(memory), "%lu", mesh_get_limits().memory_mib);

	sigemptyset(&none);
	sigemptyset(&defaults);
	sigaddset(&defaults, SIGINT);
	sigaddset(&defaults, SIGTERM);
	sigaddset(&defaults, SIGHUP);
	sigaddset(&defaults, SIGPIPE);
	posix_spawn_file_actions_init(&actions);
	posix_spawn_file_actions_adddup2(&actions, answer_fd, STDOUT_FILENO);
	if (said)
		posix_spawn_file_actions_adddup2(&actions, fileno(said), STDERR_FILENO);
	else
		posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
	posix_spawnattr_init(&attr);
	posix_spawnattr_setsigmask(&attr, &none);
	posix_spawnattr_setsigdefault(&attr, &defaults);
	posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
	err = posix_spawn(pid, helper, &actions, &attr, argv, environ);
	posix_spawnattr_destroy(&attr);
	posix_spawn_file_actions_destroy(&actions);
	if (err) {
		snprintf(reason, reason_size, "the mesh importer failed: cannot run %s: %s", helper,
			 strerror(err));
		return -1;
	}
	return 0;
}

/* ULONG_MAX: the default, worked out when first asked for. */
static struct mesh_limits limits = {MESH_TIME_LIMIT_DEFAULT, ULONG_MAX};

void mesh_set_limits(const struct mesh_limits *set)
{
	limits = *set;
}

struct mesh_limits mesh_get_limits(void)
{
	if (limits.memory_mib == ULONG_MAX) {
		long pages = sysconf(_SC_PHYS_PAGES), page_size = sysconf(_SC_PAGESIZE);

		limits.memory_mib =
			pages > 0 && page_size > 0
				? (unsigned long)((double)pages * page_size /
						  MESH_MEMORY_LIMIT_DEFAULT_SHARE / (1 << 20))
				: 0;
	}
	return limits;
}

static unsigned long importer_failures;

unsigned long mesh_importer_failures(void)
{
	return importer_failures;
}

static int import(const char *path, struct mesh_data *out, char *reason, size_t reason_size)
{
	char helper[PATH_MAX + 128];
	int fds[2], received, ret;
	FILE *said;
	pid_t pid;

	memset(out, 0, sizeof(*out));
	if (probe_file(path, reason, reason_size))
		return MESH_REFUSED;
	if (helper_path(helper, sizeof(helper))) {
		snprintf(reason, reason_size,
			 "the mesh importer failed: %s (reinstall rtcl, or "
			 "name it in " MESH_HELPER_ENV ")",
			 helper);
		return MESH_IMPORTER_FAILED;
	}
	if (pipe2(fds, O_CLOEXEC)) {
		snprintf(reason, reason_size, "the mesh importer failed: no pipe: %s",
			 strerror(errno));
		return MESH_IMPORTER_FAILED;
	}
	said = tmpfile(); /* what the helper prints (an assertion) goes in reason */
	if (start_helper(helper, path, fds[1], said, &pid, reason, reason_size)) {
		close(fds[0]);
		close(fds[1]);
		if (said)
			fclose(said);
		return MESH_IMPORTER_FAILED;
	}
	close(fds[1]);
	deadline = mesh_get_limits().seconds ? now() + (double)mesh_get_limits().seconds : 0;
	received = receive(fds[0], out, reason, reason_size);
	if (received == TIMED_OUT)
		kill(pid, SIGKILL);
	close(fds[0]); /* a helper still writing gets EPIPE and ends */
	ret = reap(helper, pid, received, said, reason, reason_size);
	if (said)
		fclose(said);
	if (ret)
		mesh_data_free(out);
	return ret;
}

int mesh_import(const char *path, struct mesh_data *out, char *reason, size_t reason_size)
{
	int ret = import(path, out, reason, reason_size);

	if (ret == MESH_IMPORTER_FAILED)
		importer_failures++; /* the scene loader runs in one thread */
	return ret;
}

/* The part of image output shared by both builds (see image.h): checks,
 * the temporary file and its rename, and the .ppm/.pfm writers. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "image.h"
#include "image_backend.h"

#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* Longest part of the target's name kept in the temporary file's name, so
 * that the latter stays under NAME_MAX (255) with its additions. */
#define TEMP_NAME_KEEP 100
#define TEMP_CREATE_TRIES 100

unsigned char image_to_8bit(float c)
{
	if (!(c > 0.0f)) /* also NaN */
		return 0;
	if (c >= 1.0f)
		return 255;
	/* 255 · c is exact in double, so this rounds the true product. */
	return (unsigned char)floor(255.0 * (double)c + 0.5);
}

static const char *base_name(const char *path)
{
	const char *slash = strrchr(path, '/');

	return slash ? slash + 1 : path;
}

/* Returns the extension with its dot, or "" when the name has none. */
static const char *file_extension(const char *path)
{
	const char *dot = strrchr(base_name(path), '.');

	return dot ? dot : "";
}

static int is_ppm(const char *ext)
{
	return strcasecmp(ext, ".ppm") == 0;
}

static int is_pfm(const char *ext)
{
	return strcasecmp(ext, ".pfm") == 0;
}

/* Copies the directory part of path ("." for none) into dir[dir_size]. */
static int directory_of(const char *path, char *dir, size_t dir_size, char *err, size_t err_size)
{
	const char *base = base_name(path);
	size_t length = (size_t)(base - path);

	if (length == 0) {
		snprintf(dir, dir_size, ".");
		return 0;
	}
	if (length > 1)
		length--; /* drop the slash, except for "/" itself */
	if (length >= dir_size) {
		image_set_error(err, err_size, "%s: %s", path, strerror(ENAMETOOLONG));
		return -1;
	}
	memcpy(dir, path, length);
	dir[length] = '\0';
	return 0;
}

/* Everything that can be checked without creating a file. */
static int check_path(const char *path, char *err, size_t err_size)
{
	const char *ext;
	char dir[PATH_MAX];
	struct stat st;

	if (!path || !*path) {
		image_set_error(err, err_size, "no output file name given");
		return -1;
	}
	ext = file_extension(path);
	if (!is_ppm(ext) && !is_pfm(ext) && image_backend_check_format(path, ext, err, err_size))
		return -1;

	if (directory_of(path, dir, sizeof(dir), err, err_size))
		return -1;
	if (stat(dir, &st)) {
		if (errno == ENOENT)
			image_set_error(err, err_size, "%s: directory \"%s\" does not exist", path,
					dir);
		else
			image_set_error(err, err_size, "%s: directory \"%s\": %s", path, dir,
					strerror(errno));
		return -1;
	}
	if (!S_ISDIR(st.st_mode)) {
		image_set_error(err, err_size, "%s: \"%s\" is not a directory", path, dir);
		return -1;
	}

	/* The rename would replace a device, pipe or socket with a regular
	 * file, which is never what was meant (think /dev/null). A symbolic
	 * link to a regular file is replaced by the new file. */
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
		image_set_error(err, err_size,
				"%s: exists and is not a regular file; refusing to replace it",
				path);
		return -1;
	}
	return 0;
}

static uint64_t splitmix64(uint64_t *state)
{
	uint64_t z = (*state += 0x9e3779b97f4a7c15u);

	z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9u;
	z = (z ^ (z >> 27)) * 0x94d049bb133111ebu;
	return z ^ (z >> 31);
}

/* Creates DIR/.NAME.tmp-PID-XXXXXX.EXT next to path, exclusively, with
 * mode 0666 less the umask like any new file. The extension is kept so that
 * OpenImageIO picks the format from the temporary name as well. Returns the
 * descriptor (open for writing) and the name in tmp[tmp_size], or -1. */
static int create_temp(const char *path, char *tmp, size_t tmp_size, char *err, size_t err_size)
{
	static const char digits[] = "0123456789abcdefghijklmnopqrstuvwxyz";
	static unsigned counter;
	const char *base = base_name(path);
	const char *ext = file_extension(path);
	struct timespec now;
	uint64_t state;
	char suffix[7];
	int tries, fd, n, i;

	clock_gettime(CLOCK_REALTIME, &now);
	state = (uint64_t)now.tv_nsec ^ ((uint64_t)now.tv_sec << 30) ^ ((uint64_t)getpid() << 42) ^
		counter++;

	for (tries = 0; tries < TEMP_CREATE_TRIES; tries++) {
		uint64_t bits = splitmix64(&state);

		for (i = 0; i < 6; i++, bits /= 36)
			suffix[i] = digits[bits % 36];
		suffix[6] = '\0';
		n = snprintf(tmp, tmp_size, "%.*s.%.*s.tmp-%ld-%s%s", (int)(base - path), path,
			     TEMP_NAME_KEEP, base, (long)getpid(), suffix, ext);
		if (n < 0 || (size_t)n >= tmp_size) {
			image_set_error(err, err_size, "%s: %s", path, strerror(ENAMETOOLONG));
			return -1;
		}
		fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
		if (fd >= 0)
			return fd;
		if (errno != EEXIST)
			break;
	}
	image_set_error(err, err_size, "%s: cannot create a file in its directory: %s", path,
			strerror(errno));
	return -1;
}

int image_check_writable(const char *path, char *err, size_t err_size)
{
	char tmp[PATH_MAX];
	int fd;

	if (check_path(path, err, err_size))
		return -1;
	fd = create_temp(path, tmp, sizeof(tmp), err, err_size);
	if (fd < 0)
		return -1;
	close(fd);
	unlink(tmp);
	return 0;
}

/* Writes s on a "# " comment line, with line breaks made spaces. */
static void write_comment(FILE *file, const char *key, const char *s)
{
	fprintf(file, "# %s: ", key);
	for (; *s; s++)
		fputc(*s == '\n' || *s == '\r' ? ' ' : *s, file);
	fputc('\n', file);
}

/* Binary PPM, 8 bits per channel, metadata in comments. */
static int write_ppm(FILE *file, const float *rgb, int width, int height,
		     const struct image_meta *meta)
{
	size_t row_length = 3 * (size_t)width;
	unsigned char *row = malloc(row_length);
	int x, y;

	if (!row)
		return -1;
	fputs("P6\n", file);
	if (meta && meta->software)
		write_comment(file, "Software", meta->software);
	if (meta && meta->description)
		write_comment(file, "ImageDescription", meta->description);
	fprintf(file, "%d %d\n255\n", width, height);

	for (y = 0; y < height; y++) {
		const float *in = rgb + (size_t)y * row_length;

		for (x = 0; x < 3 * width; x++)
			row[x] = image_to_8bit(in[x]);
		if (fwrite(row, 1, row_length, file) != row_length)
			break;
	}
	free(row);
	return ferror(file) ? -1 : 0;
}

/* PFM: linear floats, little endian (scale -1), rows from the bottom up.
 * The format has no room for metadata. */
static int write_pfm(FILE *file, const float *rgb, int width, int height)
{
	size_t row_floats = 3 * (size_t)width;
	unsigned char *row = malloc(4 * row_floats);
	size_t i;
	int y;

	if (!row)
		return -1;
	fprintf(file, "PF\n%d %d\n-1.0\n", width, height);

	for (y = height - 1; y >= 0; y--) {
		const float *in = rgb + (size_t)y * row_floats;

		for (i = 0; i < row_floats; i++) {
			uint32_t bits;

			memcpy(&bits, &in[i], 4);
			row[4 * i + 0] = (unsigned char)bits;
			row[4 * i + 1] = (unsigned char)(bits >> 8);
			row[4 * i + 2] = (unsigned char)(bits >> 16);
			row[4 * i + 3] = (unsigned char)(bits >> 24);
		}
		if (fwrite(row, 1, 4 * row_floats, file) != 4 * row_floats)
			break;
	}
	free(row);
	return ferror(file) ? -1 : 0;
}

/* fsync fails with EINVAL where the file system cannot sync; nothing to
 * report then. A deferred write error (ENOSPC, EIO) shows up here. */
static int sync_file(int fd)
{
	return fsync(fd) && errno != EINVAL ? -1 : 0;
}

/* Writes .ppm or .pfm into fd, which it closes. */
static int write_netpbm(int fd, const char *path, const float *rgb, int width, int height,
			const struct image_meta *meta, char *err, size_t err_size)
{
	FILE *file = fdopen(fd, "wb");
	int failed;

	if (!file) {
		image_set_error(err, err_size, "%s: %s", path, strerror(errno));
		close(fd);
		return -1;
	}
	errno = 0;
	if (is_pfm(file_extension(path)))
		failed = write_pfm(file, rgb, width, height);
	else
		failed = write_ppm(file, rgb, width, height, meta);
	if (!failed)
		failed = fflush(file) || sync_file(fileno(file));
	if (failed) {
		image_set_error(err, err_size, "%s: cannot write: %s", path,
				errno ? strerror(errno) : "out of memory");
		fclose(file);
		return -1;
	}
	if (fclose(file)) {
		image_set_error(err, err_size, "%s: cannot write: %s", path, strerror(errno));
		return -1;
	}
	return 0;
}

static int write_with_backend(int fd, const char *path, const char *tmp, const float *rgb,
			      int width, int height, const struct image_meta *meta, char *err,
			      size_t err_size)
{
	if (image_backend_encode(path, tmp, fd, rgb, width, height, meta, err, err_size)) {
		close(fd);
		return -1;
	}
	if (sync_file(fd) || close(fd)) {
		image_set_error(err, err_size, "%s: cannot write: %s", path, strerror(errno));
		return -1;
	}
	return 0;
}

int image_write(const char *path, const float *rgb, int width, int height,
		const struct image_meta *meta, char *err, size_t err_size)
{
	const char *ext;
	char tmp[PATH_MAX];
	int fd, failed;

	if (check_path(path, err, err_size))
		return -1;
	if (!rgb || width <= 0 || height <= 0 || (size_t)width > SIZE_MAX / 12 / (size_t)height) {
		image_set_error(err, err_size, "%s: invalid image (%d x %d pixels%s)", path, width,
				height, rgb ? "" : ", no data");
		return -1;
	}

	fd = create_temp(path, tmp, sizeof(tmp), err, err_size);
	if (fd < 0)
		return -1;
	ext = file_extension(path);
	if (is_ppm(ext) || is_pfm(ext))
		failed = write_netpbm(fd, path, rgb, width, height, meta, err, err_size);
	else
		failed = write_with_backend(fd, path, tmp, rgb, width, height, meta, err, err_size);
	if (failed)
		goto out_remove_temp;

	if (rename(tmp, path)) {
		image_set_error(err, err_size, "%s: cannot replace: %s", path, strerror(errno));
		goto out_remove_temp;
	}
	return 0;

out_remove_temp:
	unlink(tmp);
	return -1;
}

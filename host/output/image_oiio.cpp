// Image output through OpenImageIO: the format follows the extension.
// image_common.c does the checks, the temporary file and .ppm/.pfm (which
// OIIO 2.4 cannot write as PFM); this file encodes everything else.
#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include "output/image.h"
#include "output/image_backend.h"

namespace
{

const char *const format_hint = "use .png, .exr, .tif, .jpg, .hdr, .ppm, .pfm, ...";

// OIIO's messages may span lines and name the temporary file; make them one
// line about the file the user asked for.
std::string oiio_error_line(std::string message, const char *tmp_path, const char *path)
{
	const std::string tmp = tmp_path;
	size_t at;

	while ((at = message.find(tmp)) != std::string::npos)
		message.replace(at, tmp.size(), path);
	while (!message.empty() && message.back() == '\n')
		message.pop_back();
	while ((at = message.find('\n')) != std::string::npos)
		message.replace(at, 1, "; ");
	return message.empty() ? "unknown error" : message;
}

// Writes go straight to the temporary file's descriptor and the first
// failure is kept: some OIIO 2.4 writers (PNG among them) ignore a short
// write, which on a full disk would produce a truncated image and success.
class FdOutput : public OIIO::Filesystem::IOProxy
{
      public:
	FdOutput(int fd, const char *name) : IOProxy(name, Write), fd(fd)
	{
	}
	const char *proxytype() const override
	{
		return "rtcl-fd";
	}
	size_t write(const void *buf, size_t size) override
	{
		const size_t written = pwrite(buf, size, m_pos);

		m_pos += int64_t(written);
		return written;
	}
	size_t pwrite(const void *buf, size_t size, int64_t offset) override
	{
		const char *bytes = static_cast<const char *>(buf);
		size_t done = 0;

		while (done < size && !failure) {
			const ssize_t n = ::pwrite(fd, bytes + done, size - done,
						   off_t(offset) + off_t(done));
			if (n > 0)
				done += size_t(n);
			else if (n == 0)
				failure = EIO;
			else if (errno != EINTR)
				failure = errno;
		}
		end = std::max(end, offset + int64_t(done));
		return done;
	}
	size_t size() const override
	{
		return size_t(end);
	}
	// errno of the first failed write, or 0.
	int error_number() const
	{
		return failure;
	}

      private:
	int fd;
	int failure = 0;
	int64_t end = 0;
};

// Linear floats where the format stores them; 8 bits everywhere else.
bool is_float_format(const char *format_name)
{
	return std::strcmp(format_name, "openexr") == 0 || std::strcmp(format_name, "hdr") == 0;
}

// OIIO 2.4's writers that cannot give a file which reads back: "term" prints
// the image on the terminal, "null" writes nothing, and "jpeg2000" writes an
// empty (.j2k) or unreadable (.jp2) file through an I/O proxy.
bool cannot_round_trip(const char *format_name)
{
	return std::strcmp(format_name, "term") == 0 || std::strcmp(format_name, "null") == 0 ||
	       std::strcmp(format_name, "jpeg2000") == 0;
}

// The reproducible-builds convention: with SOURCE_DATE_EPOCH set, formats
// that record a date (TIFF, EXR) record that one instead of now, so that
// one render gives the same bytes every time.
void set_date(OIIO::ImageSpec &spec)
{
	const char *epoch = std::getenv("SOURCE_DATE_EPOCH");
	char *end = nullptr;
	char date[32];

	if (!epoch || !*epoch)
		return;
	errno = 0;
	const long long seconds = std::strtoll(epoch, &end, 10);
	const std::time_t when = std::time_t(seconds);
	std::tm utc;
	if (*end || errno || seconds < 0 || !gmtime_r(&when, &utc))
		return;
	std::strftime(date, sizeof(date), "%Y:%m:%d %H:%M:%S", &utc);
	spec.attribute("DateTime", date);
}

int encode(const char *path, const char *tmp_path, int tmp_fd, const float *rgb, int width,
	   int height, const struct image_meta *meta, char *err, size_t err_size)
{
	std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(tmp_path);
	FdOutput proxy(tmp_fd, tmp_path);

	if (!out) {
		image_set_error(err, err_size, "%s: OpenImageIO: %s", path,
				oiio_error_line(OIIO::geterror(), tmp_path, path).c_str());
		return -1;
	}
	// The few writers without proxy support (SGI, ICO, FITS, RLA, HEIF in
	// 2.4) open tmp_path by name; their write errors are theirs to report.
	if (out->supports("ioproxy"))
		out->set_ioproxy(&proxy);

	const bool is_float = is_float_format(out->format_name());
	OIIO::ImageSpec spec(width, height, 3,
			     is_float ? OIIO::TypeDesc::FLOAT : OIIO::TypeDesc::UINT8);
	if (meta && meta->software)
		spec.attribute("Software", meta->software);
	if (meta && meta->description)
		spec.attribute("ImageDescription", meta->description);
	set_date(spec);
	// Float formats hold linear values; 8-bit ones say how they are encoded.
	// Not TIFF: OIIO 2.4 records sRGB there in an EXIF directory, which its
	// TIFF writer cannot add through the write-only I/O proxy (the file then
	// does not read back); a TIFF has no other place for it.
	if (std::strcmp(out->format_name(), "tiff") != 0 && meta && meta->samples > 0)
		spec.attribute(IMAGE_SAMPLES_KEY, meta->samples);
	if (std::strcmp(out->format_name(), "tiff") != 0)
		spec.attribute("oiio:ColorSpace",
			       is_float || image_meta_encoding(meta) == IMAGE_LINEAR ? "linear"
										 : "sRGB");

	if (!out->open(tmp_path, spec)) {
		image_set_error(err, err_size, "%s: OpenImageIO: %s", path,
				oiio_error_line(out->geterror(), tmp_path, path).c_str());
		return -1;
	}

	bool written;
	if (is_float) {
		written = out->write_image(OIIO::TypeDesc::FLOAT, rgb);
	} else {
		std::vector<unsigned char> bytes(3 * size_t(width) * size_t(height));
		for (size_t i = 0; i < bytes.size(); i++)
			bytes[i] = image_encode_8bit(rgb[i], image_meta_encoding(meta));
		written = out->write_image(OIIO::TypeDesc::UINT8, bytes.data());
	}
	// close() even after a failed write, so that the file is released
	// before the caller removes it.
	const bool closed = out->close();
	if (proxy.error_number()) {
		image_set_error(err, err_size, "%s: cannot write: %s", path,
				std::strerror(proxy.error_number()));
		return -1;
	}
	if (!written || !closed) {
		image_set_error(err, err_size, "%s: OpenImageIO: %s", path,
				oiio_error_line(out->geterror(), tmp_path, path).c_str());
		return -1;
	}
	return 0;
}

} // namespace

extern "C" int image_backend_check_format(const char *path, const char *ext, char *err,
					  size_t err_size)
{
	// OIIO takes a name without a dot for a format name ("png"), so a
	// file called "png" would silently become a PNG: refuse it here.
	if (!*ext) {
		image_set_error(err, err_size,
				"%s: no file extension to choose an image format by (%s)", path,
				format_hint);
		return -1;
	}
	try {
		std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
		if (out && cannot_round_trip(out->format_name())) {
			image_set_error(err, err_size,
					"%s: OpenImageIO's %s writer does not give a file that "
					"reads back (%s)",
					path, out->format_name(), format_hint);
			return -1;
		}
		if (out)
			return 0;
		OIIO::geterror(); // consumed: our message says it better
	} catch (const std::exception &e) {
		image_set_error(err, err_size, "%s: OpenImageIO: %s", path, e.what());
		return -1;
	}
	image_set_error(err, err_size, "%s: unknown image format \"%s\" (%s)", path, ext,
			format_hint);
	return -1;
}

extern "C" int image_backend_encode(const char *path, const char *tmp_path, int tmp_fd,
				    const float *rgb, int width, int height,
				    const struct image_meta *meta, char *err, size_t err_size)
{
	// No exception may cross into C.
	try {
		return encode(path, tmp_path, tmp_fd, rgb, width, height, meta, err, err_size);
	} catch (const std::exception &e) {
		image_set_error(err, err_size, "%s: %s", path, e.what());
	}
	return -1;
}

extern "C" int image_backend_verify(const char *path, const char *tmp_path, int width, int height,
				    char *err, size_t err_size)
{
	try {
		std::unique_ptr<OIIO::ImageOutput> writer = OIIO::ImageOutput::create(path);
		std::unique_ptr<OIIO::ImageInput> in = OIIO::ImageInput::open(tmp_path);
		const bool ok = writer && in && std::strcmp(in->format_name(),
							    writer->format_name()) == 0 &&
				in->spec().width == width && in->spec().height == height;
		if (!in)
			OIIO::geterror(); // consumed: the message below says it
		if (ok)
			return 0;
		image_set_error(err, err_size,
				"%s: the written file does not read back as a %dx%d %s image", path,
				width, height, writer ? writer->format_name() : "");
	} catch (const std::exception &e) {
		image_set_error(err, err_size, "%s: %s", path, e.what());
	}
	return -1;
}

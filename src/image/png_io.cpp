// PNG reading and writing with libpng. libpng reports errors by longjmp; each setjmp below sits in a
// function whose locals are trivially destructible, so the jump skips no destructor, and the message is
// turned into a uvr::Error once we are back in C++.
#include <uvr/error.h>
#include <uvr/image.h>

#include <png.h>

#include <algorithm>
#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <fstream>

namespace uvr {

namespace {

/// The most pixels readPng accepts, as many as the largest image uvr renders.
constexpr uint64_t kMaxPixels = uint64_t(16384) * 16384;

/// What libpng's callbacks share: the file's bytes when reading, and the first error message.
struct PngContext {
  const uint8_t *data = nullptr;
  size_t size = 0;
  size_t offset = 0;
  char message[256] = {};
};

[[noreturn]] void onPngError(png_structp png, png_const_charp message) {
  auto *context = static_cast<PngContext *>(png_get_error_ptr(png));
  std::snprintf(context->message, sizeof(context->message), "%s", message);
  png_longjmp(png, 1);
}

void onPngWarning(png_structp, png_const_charp) {}

void readFromMemory(png_structp png, png_bytep out, png_size_t length) {
  auto *context = static_cast<PngContext *>(png_get_io_ptr(png));
  if (length > context->size - context->offset) {
    context->offset = context->size;
    png_error(png, "unexpected end of file");
  }
  std::memcpy(out, context->data + context->offset, length);
  context->offset += length;
}

std::string bytePosition(size_t offset) { return "byte " + std::to_string(offset); }

/// Reads the header and sets up the conversion to 8-bit RGB. Returns false after a libpng error.
bool readPngHeader(png_structp png, png_infop info, png_uint_32 &width, png_uint_32 &height,
                   size_t &sourceRowBytes) {
  if (setjmp(png_jmpbuf(png)))
    return false;
  png_set_user_limits(png, 65536, 65536);
  png_read_info(png, info);
  width = png_get_image_width(png, info);
  height = png_get_image_height(png, info);
  sourceRowBytes = png_get_rowbytes(png, info);

  const int colorType = png_get_color_type(png, info);
  png_set_expand(png); // palette to RGB, grey below 8 bits to 8 bits, tRNS to alpha
  png_set_scale_16(png);
  png_set_strip_alpha(png);
  if (colorType == PNG_COLOR_TYPE_GRAY || colorType == PNG_COLOR_TYPE_GRAY_ALPHA)
    png_set_gray_to_rgb(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  if (png_get_rowbytes(png, info) != size_t(width) * 3)
    png_error(png, "cannot convert the image to 8-bit RGB");
  return true;
}

bool readPngRows(png_structp png, png_infop info, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png)))
    return false;
  png_read_image(png, rows);
  png_read_end(png, info);
  return true;
}

bool writePngRows(png_structp png, png_infop info, FILE *file, int width, int height, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png)))
    return false;
  png_init_io(png, file);
  png_set_IHDR(png, info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

std::vector<png_bytep> rowPointers(uint8_t *pixels, int width, int height) {
  std::vector<png_bytep> rows(static_cast<size_t>(height));
  for (int y = 0; y < height; ++y)
    rows[size_t(y)] = pixels + size_t(y) * size_t(width) * 3;
  return rows;
}

} // namespace

void writePng(const std::string &path, const Image &image) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != size_t(image.width) * image.height * 3)
    throw Error(path, "", "cannot write an empty or inconsistent image as PNG");
  FILE *file = std::fopen(path.c_str(), "wb");
  if (!file)
    throw Error(path, "", std::string("cannot open for writing: ") + std::strerror(errno));

  PngContext context;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, onPngError, onPngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  // libpng takes row pointers to non-const data but only reads them when writing.
  std::vector<png_bytep> rows =
      rowPointers(const_cast<uint8_t *>(image.rgb.data()), image.width, image.height);
  const bool written = info && writePngRows(png, info, file, image.width, image.height, rows.data());
  png_destroy_write_struct(&png, &info);
  const bool closed = std::fclose(file) == 0;

  if (!written)
    throw Error(path, "", std::string("cannot write PNG: ") + (info ? context.message : "out of memory"));
  if (!closed)
    throw Error(path, "", std::string("cannot write PNG: ") + std::strerror(errno));
}

Image readPng(const std::string &path) {
  std::ifstream stream(path, std::ios::binary | std::ios::ate);
  const std::streamoff size = stream ? std::streamoff(stream.tellg()) : -1;
  if (size < 0)
    throw Error(path, "", "cannot open for reading");
  // The signature first, so that reading some large other file by mistake fails at once.
  std::vector<uint8_t> bytes(std::min<size_t>(size_t(size), 8));
  stream.seekg(0);
  stream.read(reinterpret_cast<char *>(bytes.data()), std::streamsize(bytes.size()));
  if (!stream || bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0)
    throw Error(path, bytePosition(0), "not a PNG file (expected the PNG signature)");
  bytes.resize(size_t(size));
  if (!stream.read(reinterpret_cast<char *>(bytes.data()) + 8, size - 8))
    throw Error(path, bytePosition(size_t(stream.gcount()) + 8), "cannot read the file");

  PngContext context;
  context.data = bytes.data();
  context.size = bytes.size();
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, onPngError, onPngWarning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw Error(path, "", "cannot read PNG: out of memory");
  }
  png_set_read_fn(png, &context, readFromMemory);

  // Destroys libpng's state before throwing, at the position where reading stopped.
  auto fail = [&](const std::string &what) {
    const size_t offset = context.offset;
    png_destroy_read_struct(&png, &info, nullptr);
    throw Error(path, bytePosition(offset), what);
  };

  png_uint_32 width = 0, height = 0;
  size_t sourceRowBytes = 0;
  if (!readPngHeader(png, info, width, height, sourceRowBytes))
    fail(context.message);
  // Deflate compresses at most about 1032:1, so a header that claims more pixels than the file could hold
  // is corrupt; this and the size limit bound the memory a malformed file can make us allocate.
  const double rawBytes = double(height) * double(sourceRowBytes + 1);
  if (rawBytes > 1100.0 * double(bytes.size()) + 65536.0)
    fail("header declares " + std::to_string(width) + "x" + std::to_string(height) +
         " pixels, more than the file's " + std::to_string(bytes.size()) + " bytes can hold");
  if (uint64_t(width) * height > kMaxPixels)
    fail("header declares " + std::to_string(width) + "x" + std::to_string(height) +
         " pixels, more than the 16384x16384 uvr reads");

  Image image(static_cast<int>(width), static_cast<int>(height));
  std::vector<png_bytep> rows = rowPointers(image.rgb.data(), image.width, image.height);
  if (!readPngRows(png, info, rows.data()))
    fail(context.message);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

} // namespace uvr

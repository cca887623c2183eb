// Image storage, file formats, atomic writes and the display transform.
#include "image/image.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "image/image_io.h"
#include "image/tonemap.h"

namespace caustica {
namespace {

namespace fs = std::filesystem;

// A fresh, empty directory per test so leftover-file checks see only that test's files.
class ImageFiles : public testing::Test {
 protected:
  void SetUp() override {
    const auto* info = testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::path(testing::TempDir()) /
           ("caustica_image_" + std::to_string(::getpid()) + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string file(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_))
      names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  void write_bytes(const std::string& path, const std::string& bytes) const {
    std::ofstream(path, std::ios::binary) << bytes;
  }
  std::string read_bytes(const std::string& path) const {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  fs::path dir_;
};

// Distinct, non-round values in every channel so a swapped channel, a flipped row or a lost
// bit shows up.
Image test_pattern(int width, int height) {
  Image image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      image.at(x, y) = Rgb(0.1f + x * 1.37f + y * 0.01f, std::ldexp(1.f + x, -y - 3) + 1e-7f * y,
                           100.f * y + 0.333f * x + 1e-5f);
  return image;
}

void expect_identical(const Image& a, const Image& b) {
  ASSERT_EQ(a.width(), b.width());
  ASSERT_EQ(a.height(), b.height());
  for (int y = 0; y < a.height(); ++y)
    for (int x = 0; x < a.width(); ++x)
      for (int c = 0; c < 3; ++c)
        ASSERT_EQ(a.at(x, y)[c], b.at(x, y)[c]) << "pixel (" << x << ", " << y << ") ch " << c;
}

template <typename F>
void expect_throws_naming(F&& f, const std::string& path) {
  try {
    f();
    FAIL() << "no exception for " << path;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(Image, StoresTopRowFirst) {
  Image image(3, 2, Rgb(0.5f));
  image.at(2, 1) = Rgb(1, 2, 3);
  EXPECT_EQ(image[5], Rgb(1, 2, 3));
  EXPECT_EQ(image.pixel_count(), 6u);
  EXPECT_EQ(image[0], Rgb(0.5f));
}

TEST(Image, AverageIsPlainMean) {
  Image image(2, 2);
  image.at(0, 0) = Rgb(1, 0, 0);
  image.at(1, 0) = Rgb(3, 4, 0);
  image.at(0, 1) = Rgb(0, 0, 8);
  EXPECT_EQ(image.average(), Rgb(1, 1, 2));
  EXPECT_EQ(Image().average(), Rgb(0.f));
}

TEST(Image, BilinearWrapExactAtTexelCentres) {
  const Image image = test_pattern(4, 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) {
      const Rgb v = image.bilinear_wrap((x + 0.5f) / 4, (y + 0.5f) / 3);
      for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(v[c], image.at(x, y)[c]);
    }
}

TEST(Image, BilinearWrapInterpolatesAcrossTheSeam) {
  Image image(2, 1);
  image.at(0, 0) = Rgb(0.f);
  image.at(1, 0) = Rgb(1.f);
  EXPECT_FLOAT_EQ(image.bilinear_wrap(0.5f, 0.5f).r, 0.5f);    // Between the two centres.
  EXPECT_FLOAT_EQ(image.bilinear_wrap(0.0f, 0.5f).r, 0.5f);    // Left edge: half the last column.
  EXPECT_FLOAT_EQ(image.bilinear_wrap(1.25f, 0.5f).r, 0.0f);   // Wraps onto texel 0's centre.
  EXPECT_FLOAT_EQ(image.bilinear_wrap(-0.25f, 0.5f).r, 1.0f);  // Wraps onto texel 1's centre.
}

TEST_F(ImageFiles, ExrRoundTripIsExact) {
  const Image image = test_pattern(7, 5);
  write_exr(image, file("a.exr"));
  expect_identical(read_image(file("a.exr")), image);
}

TEST_F(ImageFiles, PfmRoundTripIsExact) {
  const Image image = test_pattern(6, 4);
  write_pfm(image, file("a.pfm"));
  expect_identical(read_image(file("a.pfm")), image);
}

TEST_F(ImageFiles, PfmIsStoredBottomRowFirstLittleEndian) {
  Image image(1, 2);
  image.at(0, 0) = Rgb(1, 2, 3);  // Top.
  image.at(0, 1) = Rgb(4, 5, 6);  // Bottom: the first row in the file.
  write_pfm(image, file("a.pfm"));
  const std::string bytes = read_bytes(file("a.pfm"));
  const std::string header = "PF\n1 2\n-1\n";
  ASSERT_EQ(bytes.size(), header.size() + 6 * 4);
  EXPECT_EQ(bytes.substr(0, header.size()), header);
  float first;
  std::memcpy(&first, bytes.data() + header.size(), 4);
  EXPECT_EQ(first, 4.f);
}

TEST_F(ImageFiles, ReadsGreyBigEndianPfm) {
  // "Pf", positive scale: big endian, one channel; scale 2 multiplies the values.
  std::string bytes = "Pf\n2 1\n2.0\n";
  for (float v : {0.25f, -3.f}) {
    uint32_t word = std::bit_cast<uint32_t>(v);
    for (int shift = 24; shift >= 0; shift -= 8) bytes.push_back(char((word >> shift) & 0xff));
  }
  write_bytes(file("grey.pfm"), bytes);
  const Image image = read_image(file("grey.pfm"));
  ASSERT_EQ(image.width(), 2);
  ASSERT_EQ(image.height(), 1);
  EXPECT_EQ(image.at(0, 0), Rgb(0.5f));
  EXPECT_EQ(image.at(1, 0), Rgb(-6.f));
}

TEST_F(ImageFiles, PngRoundTripWithinQuantisation) {
  Image display(5, 3);
  for (size_t i = 0; i < display.pixel_count(); ++i)
    display[i] = Rgb(i / 15.f, 1.f - i / 15.f, (i * 7 % 15) / 14.f);
  display[0] = Rgb(-1.f, 2.f, std::numeric_limits<float>::quiet_NaN());  // Clamped; NaN -> 0.
  write_png_srgb(display, file("a.png"));

  const Image encoded = read_image(file("a.png"), /*srgb=*/false);
  ASSERT_EQ(encoded.width(), 5);
  ASSERT_EQ(encoded.height(), 3);
  EXPECT_EQ(encoded[0], Rgb(0.f, 1.f, 0.f));
  for (size_t i = 1; i < display.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(encoded[i][c], display[i][c], 0.5f / 255 + 1e-6f);

  // Decoding as sRGB gives the linear values the display values encode.
  const Image linear = read_image(file("a.png"), /*srgb=*/true);
  for (size_t i = 0; i < display.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(linear[i][c], srgb_to_linear(encoded[i][c]));
}

// A minimal valid PNG: one IHDR, one IDAT holding an uncompressed ("stored") zlib stream.
std::string png_chunk(const std::string& type, const std::string& data) {
  auto be32 = [](uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  const std::string body = type + data;
  uint32_t crc = 0xffffffffu;  // CRC-32 as in the PNG specification, bit by bit.
  for (unsigned char byte : body) {
    crc ^= byte;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xedb88320u & (0u - (crc & 1u)));
  }
  return be32(uint32_t(data.size())) + body + be32(~crc);
}

std::string png_16bit_rgb(int width, int height, const std::vector<uint16_t>& samples) {
  std::string raw;  // Filter type 0 per row, then big-endian 16-bit samples.
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    for (int i = 0; i < width * 3; ++i) {
      const uint16_t v = samples[size_t(y) * width * 3 + i];
      raw += {char(v >> 8), char(v & 0xff)};
    }
  }
  uint32_t a = 1, b = 0;  // Adler-32 of the uncompressed data.
  for (unsigned char byte : raw) {
    a = (a + byte) % 65521;
    b = (b + a) % 65521;
  }
  const uint16_t len = uint16_t(raw.size()), nlen = uint16_t(~len);
  // zlib header (no compression), one final stored block, then the Adler-32 big endian.
  std::string zlib = {0x78, 0x01, 0x01};
  zlib += {char(len & 0xff), char(len >> 8), char(nlen & 0xff), char(nlen >> 8)};
  zlib += raw;
  const uint32_t adler = (b << 16) | a;
  zlib += {char(adler >> 24), char(adler >> 16), char(adler >> 8), char(adler)};
  const std::string ihdr = {
      0, 0, char(width >> 8), char(width), 0, 0, char(height >> 8), char(height), 16, 2, 0, 0, 0};
  return std::string("\x89PNG\r\n\x1a\n", 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", zlib) +
         png_chunk("IEND", "");
}

TEST_F(ImageFiles, Reads16BitPngWithOptionalSrgbDecoding) {
  const std::vector<uint16_t> samples = {0, 65535, 32768, 1000, 50000, 12345};
  write_bytes(file("deep.png"), png_16bit_rgb(2, 1, samples));
  const Image encoded = read_image(file("deep.png"), /*srgb=*/false);
  const Image linear = read_image(file("deep.png"), /*srgb=*/true);
  ASSERT_EQ(encoded.width(), 2);
  ASSERT_EQ(encoded.height(), 1);
  for (int i = 0; i < 6; ++i) {
    const float v = samples[i] / 65535.f;
    EXPECT_FLOAT_EQ(encoded[i / 3][i % 3], v) << i;
    EXPECT_FLOAT_EQ(linear[i / 3][i % 3], srgb_to_linear(v)) << i;
  }
}

TEST_F(ImageFiles, TonemappedPngRoundTripRecoversLinearValues) {
  Image linear(4, 1);
  linear[0] = Rgb(0.f);
  linear[1] = Rgb(0.18f);
  linear[2] = Rgb(0.5f, 0.7f, 0.9f);
  linear[3] = Rgb(1.f);
  write_png_srgb(tonemap_srgb(linear), file("a.png"));
  const Image back = read_image(file("a.png"));
  // One 8-bit step in sRGB is at most ~1% of the linear value above black.
  for (size_t i = 0; i < linear.pixel_count(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(back[i][c], linear[i][c], 0.005f);
}

TEST_F(ImageFiles, WritersLeaveOnlyTheTargetFile) {
  const Image image = test_pattern(3, 2);
  write_exr(image, file("out.exr"));
  write_exr(image, file("out.exr"));  // Replacing an existing file goes through rename too.
  write_pfm(image, file("out.pfm"));
  write_png_srgb(tonemap_srgb(image), file("out.png"));
  write_file_atomic(file("stats.json"), "{}\n");
  EXPECT_EQ(listing(), (std::vector<std::string>{"out.exr", "out.pfm", "out.png", "stats.json"}));
}

TEST_F(ImageFiles, AtomicWriteReplacesContents) {
  write_file_atomic(file("a.txt"), "first version, longer");
  write_file_atomic(file("a.txt"), "second");
  EXPECT_EQ(read_bytes(file("a.txt")), "second");
  write_file_atomic(file("empty"), "");
  EXPECT_EQ(read_bytes(file("empty")), "");
  EXPECT_EQ(listing(), (std::vector<std::string>{"a.txt", "empty"}));
}

TEST_F(ImageFiles, FailedWriteThrowsAndLeavesNothing) {
  const std::string missing_dir = file("no/such/dir");
  const Image image = test_pattern(2, 2);
  expect_throws_naming([&] { write_exr(image, missing_dir + "/a.exr"); }, missing_dir + "/a.exr");
  expect_throws_naming([&] { write_png_srgb(image, missing_dir + "/a.png"); },
                       missing_dir + "/a.png");
  expect_throws_naming([&] { write_pfm(image, missing_dir + "/a.pfm"); }, missing_dir + "/a.pfm");
  expect_throws_naming([&] { write_file_atomic(missing_dir + "/a.txt", "x"); },
                       missing_dir + "/a.txt");
  // The target is an existing directory: the rename fails and the temporary is removed.
  fs::create_directory(file("taken.exr"));
  expect_throws_naming([&] { write_exr(image, file("taken.exr")); }, file("taken.exr"));
  EXPECT_EQ(listing(), (std::vector<std::string>{"taken.exr"}));
  EXPECT_TRUE(fs::is_empty(file("taken.exr")));
}

TEST_F(ImageFiles, ReadingMissingFileThrowsWithPath) {
  for (const char* name : {"missing.exr", "missing.pfm", "missing.png", "missing.hdr"})
    expect_throws_naming([&] { read_image(file(name)); }, file(name));
}

TEST_F(ImageFiles, ReadingTruncatedFileThrowsWithPath) {
  const Image image = test_pattern(16, 16);
  write_exr(image, file("full.exr"));
  write_pfm(image, file("full.pfm"));
  write_png_srgb(tonemap_srgb(image), file("full.png"));
  for (const char* ext : {"exr", "pfm", "png"}) {
    const std::string bytes = read_bytes(file(std::string("full.") + ext));
    // Dropping the last byte only hurts a PNG's IEND checksum, which decoders ignore; the
    // other formats need every byte of the raster.
    const size_t last = std::string(ext) == "png" ? bytes.size() / 2 : bytes.size() - 1;
    for (size_t keep : {size_t(0), size_t(5), bytes.size() / 2, last}) {
      const std::string cut = file("cut" + std::to_string(keep) + "." + ext);
      write_bytes(cut, bytes.substr(0, keep));
      expect_throws_naming([&] { read_image(cut); }, cut);
    }
  }
}

TEST_F(ImageFiles, ReadingGarbageThrowsWithPath) {
  std::string garbage;
  for (int i = 0; i < 4096; ++i) garbage.push_back(char((i * 7919 + 13) & 0xff));
  for (const char* name : {"junk.exr", "junk.pfm", "junk.png", "junk.jpg", "junk.hdr"}) {
    write_bytes(file(name), garbage);
    expect_throws_naming([&] { read_image(file(name)); }, file(name));
  }
  // Plausible headers with impossible contents.
  write_bytes(file("huge.pfm"), "PF\n100000 100000\n-1\n");
  expect_throws_naming([&] { read_image(file("huge.pfm")); }, file("huge.pfm"));
  write_bytes(file("negative.pfm"), "PF\n-3 2\n-1\n");
  expect_throws_naming([&] { read_image(file("negative.pfm")); }, file("negative.pfm"));
  write_bytes(file("words.pfm"), "PF\nthree two\n-1\n");
  expect_throws_naming([&] { read_image(file("words.pfm")); }, file("words.pfm"));
  // A PNG signature followed by junk.
  write_bytes(file("sig.png"), std::string("\x89PNG\r\n\x1a\n", 8) + garbage);
  expect_throws_naming([&] { read_image(file("sig.png")); }, file("sig.png"));
}

TEST(Tonemap, ClampsThenAppliesSrgbCurve) {
  Image linear(6, 1);
  linear[0] = Rgb(0.f);
  linear[1] = Rgb(0.5f);
  linear[2] = Rgb(1.f);
  linear[3] = Rgb(2.f);
  linear[4] =
      Rgb(-1.f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity());
  linear[5] = Rgb(0.001f);  // Linear segment of the sRGB curve.
  const Image display = tonemap_srgb(linear);
  EXPECT_EQ(display[0], Rgb(0.f));
  EXPECT_NEAR(display[1].r, 0.735357f, 1e-5f);  // 1.055 * 0.5^(1/2.4) - 0.055
  EXPECT_FLOAT_EQ(display[2].r, 1.f);
  EXPECT_FLOAT_EQ(display[3].r, 1.f);
  EXPECT_EQ(display[4].r, 0.f);
  EXPECT_EQ(display[4].g, 0.f);
  EXPECT_FLOAT_EQ(display[4].b, 1.f);
  EXPECT_FLOAT_EQ(display[5].r, 0.01292f);
}

TEST(Tonemap, ExposureScalesByPowersOfTwo) {
  Image linear(1, 1, Rgb(0.25f, 0.5f, 1.f));
  const Image plus_one = tonemap_srgb(linear, 1.f);
  EXPECT_FLOAT_EQ(plus_one[0].r, linear_to_srgb(0.5f));
  EXPECT_FLOAT_EQ(plus_one[0].g, 1.f);
  EXPECT_FLOAT_EQ(plus_one[0].b, 1.f);
  const Image minus_two = tonemap_srgb(linear, -2.f);
  EXPECT_FLOAT_EQ(minus_two[0].r, linear_to_srgb(0.0625f));
  EXPECT_FLOAT_EQ(minus_two[0].b, linear_to_srgb(0.25f));
}

}  // namespace
}  // namespace caustica

#include <cstdio>
#include <fstream>

#include <gtest/gtest.h>

#include "jpcr/io/npy.hpp"
#include "jpcr/quadric/error.hpp"
#include "temp_dir.hpp"

namespace jpcr {
namespace {

TEST(Npy, FloatRoundTripKeepsShapeAndNaN) {
  std::vector<float> data(3 * 4 * 2);
  for (std::size_t i = 0; i < data.size(); ++i)
    data[i] = 0.5f * static_cast<float>(i) - 3.0f;
  data[5] = std::numeric_limits<float>::quiet_NaN();
  test::TempDir dir;
  write_npy(dir.file("a.npy"), {3, 4, 2}, data.data());
  const NpyArray a = read_npy(dir.file("a.npy"));
  EXPECT_EQ(a.dtype, "f4");
  ASSERT_EQ(a.shape, (std::vector<std::size_t>{3, 4, 2}));
  const std::vector<float> back = a.to_float();
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (i == 5)
      EXPECT_TRUE(std::isnan(back[i]));
    else
      EXPECT_EQ(back[i], data[i]);
  }
}

TEST(Npy, HeaderIsSixtyFourByteAlignedAsNumpyWritesIt) {
  const float x[2] = {1.0f, 2.0f};
  const std::string bytes = format_npy<float>({2}, x);
  const std::size_t header_len =
      static_cast<unsigned char>(bytes[8]) | (static_cast<unsigned char>(bytes[9]) << 8);
  EXPECT_EQ((10 + header_len) % 64, 0u);
  EXPECT_EQ(bytes[10 + header_len - 1], '\n');
  EXPECT_NE(bytes.find("'shape': (2,)"), std::string::npos);
  EXPECT_EQ(bytes.size(), 10 + header_len + 8);
}

TEST(Npy, OtherDtypesConvertToFloat) {
  const std::uint16_t u[3] = {0, 5000, 65535};
  const std::string bytes = format_npy<std::uint16_t>({3}, u);
  const NpyArray a =
      parse_npy(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size(), "m");
  EXPECT_EQ(a.dtype, "u2");
  EXPECT_EQ(a.to_float(), (std::vector<float>{0.0f, 5000.0f, 65535.0f}));
  const double d[2] = {1e-300, -2.5};
  const std::string b2 = format_npy<double>({1, 2}, d);
  const NpyArray a2 = parse_npy(reinterpret_cast<const std::uint8_t*>(b2.data()), b2.size(), "m");
  EXPECT_EQ(a2.to_float()[1], -2.5f);
}

TEST(Npy, MalformedFilesAreRejectedWithTheirName) {
  const float x[4] = {1, 2, 3, 4};
  std::string good = format_npy<float>({4}, x);
  auto parse = [](const std::string& s) {
    return parse_npy(reinterpret_cast<const std::uint8_t*>(s.data()), s.size(), "bad.npy");
  };
  EXPECT_THROW(parse("not an npy file"), InputError);
  EXPECT_THROW(parse(good.substr(0, good.size() - 1)), InputError);  // truncated data
  EXPECT_THROW(parse(good.substr(0, 20)), InputError);               // truncated header
  std::string huge = good;
  huge.replace(huge.find("(4,)"), 4, "(99999999999999999999,)");
  EXPECT_THROW(parse(huge), InputError);
  std::string overflow = good;
  overflow.replace(overflow.find("(4,)"), 4, "(4294967296, 4294967296, 16)");
  EXPECT_THROW(parse(overflow), InputError);
  std::string fortran = good;
  fortran.replace(fortran.find("False"), 5, "True ");
  EXPECT_THROW(parse(fortran), InputError);
  try {
    parse("\x93NUMPY\x09\x00\x10\x00");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.npy"), std::string::npos);
  }
}

TEST(Npy, NumpyReadsWhatWeWrite) {
  // Cross-check with the real numpy when Debian's python3-numpy is installed.
  if (std::system("/usr/bin/python3 -c 'import numpy' 2>/dev/null") != 0) {
    GTEST_SKIP() << "python3-numpy not installed";
  }
  test::TempDir dir;
  const float x[6] = {1, 2, 3, 4, 5, 6};
  write_npy(dir.file("a.npy"), {2, 3}, x);
  const std::string cmd = "/usr/bin/python3 -c \"import numpy as np; a = np.load('" +
                          dir.file("a.npy") +
                          "'); assert a.shape == (2, 3) and a.dtype == np.float32 and "
                          "a[1, 2] == 6\"";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
  const std::string write_cmd = "/usr/bin/python3 -c \"import numpy as np; np.save('" +
                                dir.file("b.npy") +
                                "', np.arange(12, dtype=np.float64).reshape(3, 4))\"";
  ASSERT_EQ(std::system(write_cmd.c_str()), 0);
  const NpyArray b = read_npy(dir.file("b.npy"));
  EXPECT_EQ(b.shape, (std::vector<std::size_t>{3, 4}));
  EXPECT_EQ(b.to_float()[11], 11.0f);
}

}  // namespace
}  // namespace jpcr

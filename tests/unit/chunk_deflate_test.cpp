// The store's own chunk encoder (src/io/chunk_deflate.hpp) against independent truths: Adler-32 of
// RFC 1950's published examples, the shuffle as HDF5 documents it (byte b of element i at b·n + i),
// and every chunk read back by the HDF5 library's own filters (its inflate and unshuffle) equal to
// the rows pushed: periodic, constant and random columns, one- and two-dimensional, whole chunks
// written directly and partial ones through the library, across several flushes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "io/chunk_deflate.hpp"
#include "io/h5_file.hpp"

namespace {

using vibro::h5::Adler32;

TEST(ChunkDeflate, Adler32KnownValues) {
  const auto adler = [](const std::string& s) {
    return Adler32(1, reinterpret_cast<const unsigned char*>(s.data()), s.size());
  };
  EXPECT_EQ(adler(""), 1u);
  EXPECT_EQ(adler("a"), 0x00620062u);
  EXPECT_EQ(adler("abc"), 0x024d0127u);
  EXPECT_EQ(adler("Wikipedia"), 0x11E60398u);
  // Long input (several blocks, a tail that is not a multiple of 16): against the definition,
  // byte by byte with the modulus at every step.
  std::vector<unsigned char> v(100003);
  std::mt19937 g(7);
  for (auto& x : v) x = static_cast<unsigned char>(g() % 256 == 0 ? 255 : g());
  std::uint32_t a = 1, b = 0;
  for (unsigned char x : v) {
    a = (a + x) % 65521;
    b = (b + a) % 65521;
  }
  EXPECT_EQ(Adler32(1, v.data(), v.size()), (b << 16) | a);
  std::vector<unsigned char> ff(70000, 0xff);  // the largest sums per block
  a = 1, b = 0;
  for (unsigned char x : ff) {
    a = (a + x) % 65521;
    b = (b + a) % 65521;
  }
  EXPECT_EQ(Adler32(1, ff.data(), ff.size()), (b << 16) | a);
}

TEST(ChunkDeflate, ShuffleIsHdf5sByteTranspose) {
  std::mt19937 g(3);
  for (size_t elem : {1u, 2u, 4u, 8u})
    // 37: not a multiple of 8 nor 16 (the 16-element SIMD loop, the 8-element loop and the tail);
    // 16 384 + 21: a store chunk and a tail.
    for (size_t count : {size_t{1}, size_t{16}, size_t{37}, size_t{16384 + 21}}) {
      std::vector<unsigned char> in(count * elem), out(in.size());
      for (auto& x : in) x = static_cast<unsigned char>(g());
      vibro::h5::Shuffle(in.data(), in.size(), elem, out.data());
      for (size_t i = 0; i < count; ++i)
        for (size_t b = 0; b < elem; ++b)
          ASSERT_EQ(out[b * count + i], in[i * elem + b]) << elem << " " << count << " " << i;
    }
}

// A table written through h5::Column (whole chunks by the encoder, the rest by the library) reads
// back, through HDF5's own filters, as the rows pushed.
TEST(ChunkDeflate, ColumnsReadBackThroughHdf5) {
  const std::string path = "/tmp/vibro_chunk_deflate_test_" + std::to_string(getpid()) + ".h5";
  std::mt19937_64 g(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const size_t rows = 5 * 16384 + 1234;
  std::vector<double> periodic(rows), random(rows), wide(rows * 3), nan(rows, std::nan("")), pieces(rows);
  std::vector<std::int64_t> count(rows);
  std::vector<std::int8_t> flag(rows);
  std::vector<double> period(36);
  for (double& p : period) p = u(g);
  for (size_t i = 0; i < rows; ++i) {
    periodic[i] = period[i % 36];
    random[i] = u(g) * 1e3;
    count[i] = static_cast<std::int64_t>(i / 36);
    flag[i] = static_cast<std::int8_t>(i % 5 == 0);
    // Constant chunks (encoded once, then copied): 0.5 in chunks 0 and 1, −3 in chunk 2, 0.5 again
    // in chunk 3, one other value in chunk 4, 0 in the last (part-filled, padded with zeros).
    const size_t chunk = i / 16384;
    pieces[i] = chunk == 2 ? -3.0 : chunk == 5 ? 0.0 : chunk == 4 && i % 16384 == 100 ? 7.0 : 0.5;
    for (size_t c = 0; c < 3; ++c) wide[i * 3 + c] = c == 1 ? 0.25 : u(g);
  }
  {
    vibro::h5::Handle file = vibro::h5::CreateFile(path);
    ASSERT_TRUE(file);
    vibro::h5::Column cp(file.get(), "periodic", vibro::h5::Type::F64(), 0);
    vibro::h5::Column cr(file.get(), "random", vibro::h5::Type::F64(), 0);
    vibro::h5::Column cc(file.get(), "count", vibro::h5::Type::I64(), 0);
    vibro::h5::Column cf(file.get(), "flag", vibro::h5::Type::I8(), 0);
    vibro::h5::Column cw(file.get(), "wide", vibro::h5::Type::F64(), 3);
    vibro::h5::Column cn(file.get(), "nan", vibro::h5::Type::F64(), 0);
    vibro::h5::Column cq(file.get(), "pieces", vibro::h5::Type::F64(), 0);
    Eigen::VectorXd row(3);
    // Flushes at a partial chunk (the library's path, read back and merged later), of whole
    // chunks only, and of everything at the end.
    const size_t cuts[] = {5000, 40000, 2 * 16384 + 16383, rows};
    size_t at = 0;
    for (size_t k = 0; k < 4; ++k) {
      for (; at < cuts[k]; ++at) {
        cp.Push(periodic[at]);
        cr.Push(random[at]);
        cc.Push(count[at]);
        cf.Push(flag[at]);
        cn.Push(nan[at]);
        cq.Push(pieces[at]);
        row << wide[at * 3], wide[at * 3 + 1], wide[at * 3 + 2];
        cw.PushRow(row);
      }
      for (vibro::h5::Column* c : {&cp, &cr, &cc, &cf, &cw, &cn, &cq}) {
        c->Stage(k == 1);
        c->WriteStaged();
      }
    }
    for (vibro::h5::Column* c : {&cp, &cr, &cc, &cf, &cw, &cn, &cq}) c->Flush();
    std::vector<double> d(rows), w(rows * 3);
    std::vector<std::int64_t> n(rows);
    std::vector<std::int8_t> f(rows);
    ASSERT_EQ(cp.rows(), rows);
    ASSERT_EQ(cw.rows(), rows);
    cp.Read(0, rows, d.data());
    EXPECT_EQ(std::memcmp(d.data(), periodic.data(), rows * 8), 0);
    cr.Read(0, rows, d.data());
    EXPECT_EQ(std::memcmp(d.data(), random.data(), rows * 8), 0);
    cc.Read(0, rows, n.data());
    EXPECT_EQ(n, count);
    cf.Read(0, rows, f.data());
    EXPECT_EQ(f, flag);
    cn.Read(0, rows, d.data());
    EXPECT_EQ(std::memcmp(d.data(), nan.data(), rows * 8), 0);
    cq.Read(0, rows, d.data());
    EXPECT_EQ(std::memcmp(d.data(), pieces.data(), rows * 8), 0);
    cw.Read(0, rows, w.data());
    EXPECT_EQ(std::memcmp(w.data(), wide.data(), rows * 3 * 8), 0);
  }
  std::remove(path.c_str());
}

}  // namespace

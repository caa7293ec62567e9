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
#include <zlib.h>

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

// Adler32 asks the processor for AVX2 itself (cpuid and xgetbv, not libgcc's cpuinfo, whose
// constructor would run at every start): it must find what libgcc's __builtin_cpu_supports finds.
TEST(ChunkDeflate, Avx2DetectedAsLibgccDetectsIt) {
#if defined(__x86_64__) && defined(__GNUC__)
  EXPECT_EQ(vibro::h5::Adler32UsesAvx2(), __builtin_cpu_supports("avx2") != 0);
#else
  EXPECT_FALSE(vibro::h5::Adler32UsesAvx2());
#endif
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

// The zlib stream of ZlibFixed, inflated by zlib itself (an independent decoder), gives back its
// input: bytes that repeat (fixed-Huffman matches), runs that do not (stored blocks, one longer
// than a stored block's 65 535 bytes), the two interleaved, short inputs, and the padded chunk of
// ShuffleDeflatePadded equal to ShuffleDeflate of the rows padded with zeros.
TEST(ChunkDeflate, StreamsInflateWithZlib) {
  std::mt19937 g(5);
  const auto round_trip = [](const std::vector<unsigned char>& in) {
    std::vector<unsigned char> z;
    vibro::h5::ZlibFixed(in.data(), in.size(), z);
    EXPECT_LE(z.size(), vibro::h5::ZlibFixedBound(in.size()));
    std::vector<unsigned char> back(in.size() + 16);
    uLongf len = back.size();
    EXPECT_EQ(uncompress(back.data(), &len, z.data(), z.size()), Z_OK) << in.size();
    back.resize(len);
    EXPECT_EQ(back, in) << in.size();
    return z.size();
  };
  for (size_t n : {size_t{0}, size_t{1}, size_t{4}, size_t{127}, size_t{128}, size_t{129}, size_t{1000},
                   size_t{65535}, size_t{65536 + 300}, size_t{200000}}) {
    std::vector<unsigned char> random(n), mixed(n), periodic(n);
    for (auto& x : random) x = static_cast<unsigned char>(g());
    // Runs of 37-byte periods and of random bytes, 50 to 2000 bytes long in turn.
    for (size_t i = 0; i < n;) {
      const size_t run = 50 + g() % 1950;
      const bool repeats = (i / 7) % 2 == 0;
      for (size_t k = 0; k < run && i < n; ++k, ++i)
        mixed[i] = repeats ? static_cast<unsigned char>(k % 37) : static_cast<unsigned char>(g());
      for (size_t k = 0; k < 8 && i < n; ++k, ++i) mixed[i] = static_cast<unsigned char>(g());
    }
    for (size_t i = 0; i < n; ++i) periodic[i] = static_cast<unsigned char>((i % 36) * 7);
    const size_t random_size = round_trip(random);
    round_trip(mixed);
    const size_t periodic_size = round_trip(periodic);
    // Random bytes cost their own size and a few bytes per stored block; a period, little.
    EXPECT_LE(random_size, n + 16 + 16 * (n / 65535));
    if (n >= 1000) {
      EXPECT_LT(periodic_size, n / 10);
    }
  }
  // A part-filled chunk: ShuffleDeflatePadded of its rows as ShuffleDeflate of the padded rows.
  for (size_t elem : {size_t{1}, size_t{4}, size_t{8}})
    for (size_t count : {size_t{1}, size_t{37}, size_t{1000}}) {
      const size_t chunk = 2048 * elem;
      std::vector<unsigned char> rows(chunk, 0);
      for (size_t i = 0; i < count * elem; ++i) rows[i] = static_cast<unsigned char>(g());
      vibro::h5::Bytes scratch;
      std::vector<unsigned char> whole(vibro::h5::ZlibFixedBound(chunk)), padded(whole.size());
      const size_t a = vibro::h5::ShuffleDeflate(rows.data(), chunk, elem, scratch, whole.data());
      std::fill(scratch.begin(), scratch.end(), 0xAB);  // stale bytes that the zeros must replace
      const size_t b = vibro::h5::ShuffleDeflatePadded(rows.data(), count * elem, chunk, elem, scratch, padded.data());
      whole.resize(a);
      padded.resize(b);
      EXPECT_EQ(padded, whole) << elem << " " << count;
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

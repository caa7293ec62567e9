// The store's chunk encoder (chunk_deflate.hpp): HDF5's shuffle, then a zlib stream of one
// fixed-Huffman deflate block (RFC 1950, RFC 1951 §3.2.6).
#include "io/chunk_deflate.hpp"

#include <algorithm>
#include <array>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__x86_64__) && defined(__GNUC__)
#include <cpuid.h>
#include <immintrin.h>
#endif

namespace vibro::h5 {

namespace {

std::uint32_t Load32(const unsigned char* p) {
  std::uint32_t v;
  std::memcpy(&v, p, 4);
  return v;
}
std::uint64_t Load64(const unsigned char* p) {
  std::uint64_t v;
  std::memcpy(&v, p, 8);
  return v;
}

// A Huffman code as the bit stream carries it: deflate sends a code's most significant bit first,
// and the stream is filled from each byte's least significant bit.
std::uint32_t Reverse(std::uint32_t code, int len) {
  std::uint32_t r = 0;
  for (int k = 0; k < len; ++k) r |= ((code >> k) & 1u) << (len - 1 - k);
  return r;
}

// Bits and their count, ready to send: a literal, a length (its code and extra bits), a distance.
struct Code {
  std::uint32_t bits;
  std::uint32_t len;
};

// The fixed codes (RFC 1951 §3.2.6) and, per match length 3…258 and distance 1…32768, its code with
// its extra bits.
struct Tables {
  std::array<Code, 288> lit{};
  std::array<Code, 259> length{};
  std::array<Code, 32769> dist{};
  Tables() {
    for (std::uint32_t v = 0; v < 288; ++v) {
      std::uint32_t code = 0, len = 0;
      if (v < 144) code = 0x30 + v, len = 8;
      else if (v < 256) code = 0x190 + (v - 144), len = 9;
      else if (v < 280) code = v - 256, len = 7;
      else code = 0xC0 + (v - 280), len = 8;
      lit[v] = {Reverse(code, static_cast<int>(len)), len};
    }
    for (std::uint32_t L = 3; L <= 258; ++L) {
      std::uint32_t sym = 0, extra = 0, val = 0;
      const std::uint32_t x = L - 3;
      if (L == 258) {
        sym = 285;
      } else if (x < 8) {
        sym = 257 + x;
      } else {
        const std::uint32_t msb = 31u - static_cast<std::uint32_t>(__builtin_clz(x));
        sym = 257 + 4 * (msb - 1) + ((x >> (msb - 2)) & 3u);
        extra = msb - 2;
        val = x & ((1u << extra) - 1u);
      }
      const Code c = lit[sym];
      length[L] = {c.bits | (val << c.len), c.len + extra};
    }
    for (std::uint32_t d = 1; d <= 32768; ++d) {
      std::uint32_t sym = 0, extra = 0, val = 0;
      const std::uint32_t x = d - 1;
      if (d <= 4) {
        sym = x;
      } else {
        const std::uint32_t msb = 31u - static_cast<std::uint32_t>(__builtin_clz(x));
        sym = 2 * msb + ((x >> (msb - 1)) & 1u);
        extra = msb - 1;
        val = x & ((1u << extra) - 1u);
      }
      dist[d] = {Reverse(sym, 5) | (val << 5), 5 + extra};
    }
  }
};

const Tables& FixedTables() {
  static const Tables t;
  return t;
}

// The bit stream: up to 32 bits per Put (a match's length and distance codes with their extra bits
// are at most 8 + 5 + 5 + 13 = 31).
class BitWriter {
 public:
  explicit BitWriter(unsigned char* out) : base_(out), out_(out) {}
  void Put(std::uint32_t bits, std::uint32_t len) {
    acc_ |= static_cast<std::uint64_t>(bits) << count_;
    count_ += len;
    if (count_ >= 32) {
      const auto word = static_cast<std::uint32_t>(acc_);
      std::memcpy(out_, &word, 4);  // little-endian, as the stream's byte order
      out_ += 4;
      acc_ >>= 32;
      count_ -= 32;
    }
  }
  // The position of the next bit, from the start of the stream.
  size_t BitPosition() const { return static_cast<size_t>(out_ - base_) * 8 + count_; }
  // Sets bit `pos` (already put) to 1.
  void SetBit(size_t pos) {
    const size_t flushed = static_cast<size_t>(out_ - base_) * 8;
    if (pos < flushed) base_[pos / 8] |= static_cast<unsigned char>(1u << (pos % 8));
    else acc_ |= std::uint64_t{1} << (pos - flushed);
  }
  // The last bits, padded to a whole byte; returns where the next byte goes (the writer may go on
  // with Put from there: Restart).
  unsigned char* Finish() {
    while (count_ > 0) {
      *out_++ = static_cast<unsigned char>(acc_);
      acc_ >>= 8;
      count_ = count_ > 8 ? count_ - 8 : 0;
    }
    acc_ = 0;
    return out_;
  }
  // Goes on at `at`, a byte boundary after what Finish returned.
  void Restart(unsigned char* at) { out_ = at; }

 private:
  unsigned char* base_;
  unsigned char* out_;
  std::uint64_t acc_ = 0;
  std::uint32_t count_ = 0;
};

constexpr int kHashBits = 15;
constexpr size_t kWindow = 32768;  // deflate's largest distance
constexpr size_t kMaxMatch = 258;
// Literal runs of this many bytes or more are stored blocks; after 2^kSkipShift misses in a row the
// search skips positions (ZlibFixed).
constexpr size_t kStoredRun = 128;
constexpr int kSkipShift = 4;

}  // namespace

void ShuffleInto(const unsigned char* in, size_t count, size_t elem, unsigned char* out, size_t stride) {
  if (elem == 1) {
    if (count > 0) std::memcpy(out, in, count);
    return;
  }
  if (elem == 8) {
    size_t i = 0;
#if defined(__SSE2__)
    // Sixteen elements (128 bytes) at a time: a 16 × 8 byte transpose in four rounds of unpacks
    // (bytes, 16-bit words, 32-bit words, 64-bit halves), then one 16-byte store to each byte plane.
    for (; i + 16 <= count; i += 16) {
      __m128i a[8], b[8];
      for (int k = 0; k < 8; ++k) {
        a[k] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(in + i * 8 + 16 * static_cast<size_t>(k)));
        // Elements 2k and 2k + 1 byte by byte: e0b0 e1b0 e0b1 e1b1 … e0b7 e1b7.
        b[k] = _mm_unpacklo_epi8(a[k], _mm_shuffle_epi32(a[k], 0x4e));
      }
      for (int k = 0; k < 4; ++k) {  // four elements: bytes 0–3 of them, then 4–7
        a[2 * k] = _mm_unpacklo_epi16(b[2 * k], b[2 * k + 1]);
        a[2 * k + 1] = _mm_unpackhi_epi16(b[2 * k], b[2 * k + 1]);
      }
      for (int k = 0; k < 2; ++k) {  // eight elements: bytes 0–1, 2–3, 4–5, 6–7
        b[4 * k] = _mm_unpacklo_epi32(a[4 * k], a[4 * k + 2]);
        b[4 * k + 1] = _mm_unpackhi_epi32(a[4 * k], a[4 * k + 2]);
        b[4 * k + 2] = _mm_unpacklo_epi32(a[4 * k + 1], a[4 * k + 3]);
        b[4 * k + 3] = _mm_unpackhi_epi32(a[4 * k + 1], a[4 * k + 3]);
      }
      for (int k = 0; k < 4; ++k) {  // sixteen elements: byte 2k, then byte 2k + 1
        const __m128i lo = _mm_unpacklo_epi64(b[k], b[k + 4]), hi = _mm_unpackhi_epi64(b[k], b[k + 4]);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + static_cast<size_t>(2 * k) * stride + i), lo);
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + static_cast<size_t>(2 * k + 1) * stride + i), hi);
      }
    }
#endif
    // Eight elements at a time: an 8 × 8 transpose of their bytes in three rounds of swaps (blocks
    // of 4, 2 and 1 bytes), then one 8-byte store to each byte plane.
    for (; i + 8 <= count; i += 8) {
      std::uint64_t a[8];
      for (int r = 0; r < 8; ++r) a[r] = Load64(in + (i + static_cast<size_t>(r)) * 8);
      constexpr std::uint64_t kMask[3] = {0x00000000FFFFFFFFull, 0x0000FFFF0000FFFFull, 0x00FF00FF00FF00FFull};
      for (int round = 0, s = 4; round < 3; ++round, s /= 2)
        for (int r = 0; r < 8; ++r) {
          if (r & s) continue;
          const std::uint64_t t = ((a[r] >> (8 * s)) ^ a[r + s]) & kMask[round];
          a[r + s] ^= t;
          a[r] ^= t << (8 * s);
        }
      for (size_t b = 0; b < 8; ++b) std::memcpy(out + b * stride + i, &a[b], 8);
    }
    for (; i < count; ++i)
      for (size_t b = 0; b < 8; ++b) out[b * stride + i] = in[i * 8 + b];
  } else {
    for (size_t i = 0; i < count; ++i)
      for (size_t b = 0; b < elem; ++b) out[b * stride + i] = in[i * elem + b];
  }
}

void Shuffle(const unsigned char* in, size_t n, size_t elem, unsigned char* out) {
  const size_t count = elem > 0 ? n / elem : 0;
  if (elem <= 1 || count <= 1) {
    if (n > 0) std::memcpy(out, in, n);
    return;
  }
  ShuffleInto(in, count, elem, out, count);
  // Bytes after the last whole element (none in the store's chunks) stay as they are, as the filter's.
  if (count * elem < n) std::memcpy(out + count * elem, in + count * elem, n - count * elem);
}

#if defined(__x86_64__) && defined(__GNUC__)
namespace {

// Adler32's sums over the first n bytes, n a multiple of 32, with AVX2 (the same sums as below, 32
// bytes per group: psadbw for the sums, pmaddubsw then pmaddwd for the bytes weighed 32 … 1); used
// when the processor has AVX2 (Adler32 asks it once).
__attribute__((target("avx2"))) void Adler32Avx2(std::uint64_t& a, std::uint64_t& b, const unsigned char* p,
                                                 size_t n) {
  constexpr std::uint32_t kMod = 65521;
  constexpr size_t kLanes = 32, kBlock = 4096;
  const __m256i zero = _mm256_setzero_si256(), ones = _mm256_set1_epi16(1);
  const __m256i weights = _mm256_setr_epi8(32, 31, 30, 29, 28, 27, 26, 25, 24, 23, 22, 21, 20, 19, 18, 17, 16, 15, 14,
                                           13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1);
  while (n > 0) {
    const size_t k = std::min(n, kBlock);
    __m256i v_sum = zero, v_ps = zero, v_w = zero;
    for (size_t g = 0; g < k; g += kLanes) {
      const __m256i x = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p + g));
      v_ps = _mm256_add_epi32(v_ps, v_sum);
      v_sum = _mm256_add_epi32(v_sum, _mm256_sad_epu8(x, zero));
      v_w = _mm256_add_epi32(v_w, _mm256_madd_epi16(_mm256_maddubs_epi16(x, weights), ones));
    }
    alignas(32) std::uint32_t l_sum[8], l_ps[8], l_w[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(l_sum), v_sum);
    _mm256_store_si256(reinterpret_cast<__m256i*>(l_ps), v_ps);
    _mm256_store_si256(reinterpret_cast<__m256i*>(l_w), v_w);
    std::uint64_t sum = 0, ps = 0, weighted = 0;
    for (int l = 0; l < 8; ++l) {
      sum += l_sum[l];
      ps += l_ps[l];
      weighted += l_w[l];
    }
    b = (b + k * a + kLanes * ps + weighted) % kMod;
    a = (a + sum) % kMod;
    p += k;
    n -= k;
  }
}

// Whether the processor and the operating system let AVX2 code run: CPUID.1:ECX's OSXSAVE and AVX,
// XCR0 keeping the XMM and YMM states (xgetbv), CPUID.(7,0):EBX's AVX2 (what libgcc's
// __builtin_cpu_supports("avx2") tests). Asked on the first Adler32, not with
// __builtin_cpu_supports, which links libgcc's cpuinfo.o into libvibro and with it a constructor
// that runs a dozen `cpuid`s at every start of every process (each traps to the hypervisor on a
// virtual machine: 3 % of the CPU of a short `vibro simulate`, docs/performance.md, "Start-up"),
// although only the HDF5 store's encoder asks.
bool HasAvx2() {
  unsigned a = 0, b = 0, c = 0, d = 0;
  if (__get_cpuid(1, &a, &b, &c, &d) == 0 || (c & bit_OSXSAVE) == 0 || (c & bit_AVX) == 0) return false;
  unsigned xcr0_lo = 0, xcr0_hi = 0;
  __asm__ volatile("xgetbv" : "=a"(xcr0_lo), "=d"(xcr0_hi) : "c"(0));
  if ((xcr0_lo & 6u) != 6u) return false;
  if (__get_cpuid_count(7, 0, &a, &b, &c, &d) == 0) return false;
  return (b & bit_AVX2) != 0;
}

}  // namespace
#endif

bool Adler32UsesAvx2() {
#if defined(__x86_64__) && defined(__GNUC__)
  static const bool avx2 = HasAvx2();
  return avx2;
#else
  return false;
#endif
}

std::uint32_t Adler32(std::uint32_t adler, const unsigned char* p, size_t n) {
  constexpr std::uint32_t kMod = 65521;
  constexpr size_t kLanes = 16, kBlock = 4096;
  std::uint64_t a = adler & 0xffffu, b = adler >> 16;
#if defined(__x86_64__) && defined(__GNUC__)
  if (n >= 32 && Adler32UsesAvx2()) {
    const size_t whole = n / 32 * 32;
    Adler32Avx2(a, b, p, whole);
    p += whole;
    n -= whole;
  }
#endif
  // Per block of k bytes (groups g = 0 … m − 1 of 16, k = 16 m): a += Σ x, and
  // b += k·a + 16 Σ_g (m − 1 − g) S_g + Σ_g Σ_j (16 − j) x_gj, S_g the sum of group g's bytes: the
  // first sum accumulates the groups' sums before each group (ps), the second weighs each group's
  // bytes by 16 … 1 (w). All of it fits 32-bit lanes for k ≤ 4096, reduced mod 65521 after each block.
  while (n >= kLanes) {
    const size_t k = std::min(n, kBlock) / kLanes * kLanes;
    std::uint64_t sum = 0, ps = 0, weighted = 0;
#if defined(__SSE2__)
    // psadbw sums a group's 16 bytes; pmaddwd weighs them (bytes widened to 16 bits) by 16 … 1.
    const __m128i zero = _mm_setzero_si128();
    const __m128i w_lo = _mm_setr_epi16(16, 15, 14, 13, 12, 11, 10, 9), w_hi = _mm_setr_epi16(8, 7, 6, 5, 4, 3, 2, 1);
    __m128i v_sum = zero, v_ps = zero, v_w = zero;
    for (size_t g = 0; g < k; g += kLanes) {
      const __m128i x = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + g));
      v_ps = _mm_add_epi32(v_ps, v_sum);
      v_sum = _mm_add_epi32(v_sum, _mm_sad_epu8(x, zero));
      v_w = _mm_add_epi32(v_w, _mm_madd_epi16(_mm_unpacklo_epi8(x, zero), w_lo));
      v_w = _mm_add_epi32(v_w, _mm_madd_epi16(_mm_unpackhi_epi8(x, zero), w_hi));
    }
    alignas(16) std::uint32_t l_sum[4], l_ps[4], l_w[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(l_sum), v_sum);
    _mm_store_si128(reinterpret_cast<__m128i*>(l_ps), v_ps);
    _mm_store_si128(reinterpret_cast<__m128i*>(l_w), v_w);
    for (int l = 0; l < 4; ++l) {
      sum += l_sum[l];
      ps += l_ps[l];
      weighted += l_w[l];
    }
#else
    for (size_t g = 0; g < k; g += kLanes) {
      ps += sum;
      for (size_t j = 0; j < kLanes; ++j) {
        sum += p[g + j];
        weighted += (kLanes - j) * p[g + j];
      }
    }
#endif
    b = (b + k * a + kLanes * ps + weighted) % kMod;
    a = (a + sum) % kMod;
    p += k;
    n -= k;
  }
  for (; n > 0; --n, ++p) {
    a += *p;
    b += a;
  }
  a %= kMod;
  b %= kMod;
  return static_cast<std::uint32_t>((b << 16) | a);
}

size_t ZlibFixedBound(size_t n) {
  // At most 9 bits per byte, the header, the block's 3 bits and its end, the Adler-32, and the 4
  // bytes a Put may write at once.
  return n + n / 8 + 32;
}

void ZlibFixed(const unsigned char* in, size_t n, std::vector<unsigned char>& out) {
  out.resize(ZlibFixedBound(n));
  out.resize(ZlibFixed(in, n, out.data()));
}

size_t ZlibFixed(const unsigned char* in, size_t n, unsigned char* out) {
  const Tables& t = FixedTables();
  unsigned char* o = out;
  *o++ = 0x78;  // CM = 8 (deflate), CINFO = 7 (32 KiB window)
  *o++ = 0x01;  // FLEVEL 0, FCHECK: 0x7801 is a multiple of 31
  BitWriter bw(o);
  size_t block = bw.BitPosition();  // the current fixed block's header (its BFINAL bit, set at the end)
  bw.Put(2, 3);  // BFINAL = 0, BTYPE = 01 (fixed Huffman codes)
  // The bytes [lit, i) found no match: sent as literals of the fixed code when a match or the end
  // comes, or, a run of kStoredRun bytes or more, as stored blocks (RFC 1951 §3.2.4) between two
  // fixed ones: a literal costs 8 or 9 bits, a stored byte 8, and a stored block is written by
  // memcpy (the byte planes of a column such as t, which seldom repeat, are most of the encoding).
  size_t lit = 0;
  const auto send_literals = [&](size_t end) {
    if (end - lit >= kStoredRun) {
      bw.Put(t.lit[256].bits, t.lit[256].len);  // end of the fixed block
      while (lit < end) {
        const size_t len = std::min<size_t>(end - lit, 65535);
        bw.Put(0, 3);  // BFINAL = 0, BTYPE = 00 (stored), then the next byte boundary
        unsigned char* p = bw.Finish();
        p[0] = static_cast<unsigned char>(len);
        p[1] = static_cast<unsigned char>(len >> 8);
        p[2] = static_cast<unsigned char>(~len);
        p[3] = static_cast<unsigned char>(~len >> 8);
        std::memcpy(p + 4, in + lit, len);
        bw.Restart(p + 4 + len);
        lit += len;
      }
      block = bw.BitPosition();
      bw.Put(2, 3);  // a fixed block again
      return;
    }
    for (; lit < end; ++lit) {
      const Code& l = t.lit[in[lit]];
      bw.Put(l.bits, l.len);
    }
  };
  // The hash table of the last position of each 4-byte string. It is not cleared between chunks: a
  // stale entry is checked like any other (a position before i whose 4 bytes match).
  static thread_local std::vector<std::uint32_t> table(size_t{1} << kHashBits, 0);
  std::uint32_t* head = table.data();
  size_t i = 0, rep = 0, misses = 0;
  while (i + 4 <= n) {
    const std::uint32_t cur = Load32(in + i);
    size_t d = 0;
    if (rep != 0 && rep <= i && Load32(in + i - rep) == cur) {
      d = rep;  // the last match's distance: a periodic column's period
    } else {
      const std::uint32_t h = (cur * 2654435761u) >> (32 - kHashBits);
      const std::uint32_t c = head[h];
      head[h] = static_cast<std::uint32_t>(i);
      if (c < i && i - c <= kWindow && Load32(in + c) == cur) d = i - c;
    }
    if (d == 0) {
      // No match here: after kSkipAfter misses in a row the search looks at every second position,
      // then every third, … (the bytes passed over are literals), so that bytes that do not repeat
      // cost little more than their copy; a match resets it.
      i += 1 + (misses++ >> kSkipShift);
      continue;
    }
    misses = 0;
    const size_t max_len = std::min(kMaxMatch, n - i);
    size_t len = 4;
#if defined(__SSE2__)
    // 32 bytes per step (a periodic column's matches are mostly of the longest length, 258).
    while (len + 32 <= max_len) {
      const auto* a = reinterpret_cast<const __m128i*>(in + i + len);
      const auto* b = reinterpret_cast<const __m128i*>(in + i + len - d);
      const auto lo = static_cast<std::uint32_t>(
          _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_loadu_si128(a), _mm_loadu_si128(b))));
      const auto hi = static_cast<std::uint32_t>(
          _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_loadu_si128(a + 1), _mm_loadu_si128(b + 1))));
      const std::uint32_t differ = ~(lo | (hi << 16));
      if (differ != 0) {
        len += static_cast<size_t>(__builtin_ctz(differ));
        goto matched;
      }
      len += 32;
    }
#endif
    for (;;) {
      if (len + 8 <= max_len) {
        const std::uint64_t x = Load64(in + i + len) ^ Load64(in + i + len - d);
        if (x != 0) {
          len += static_cast<size_t>(__builtin_ctzll(x)) / 8;
          break;
        }
        len += 8;
        continue;
      }
      while (len < max_len && in[i + len] == in[i + len - d]) ++len;
      break;
    }
#if defined(__SSE2__)
  matched:
#endif
    send_literals(i);
    const Code& lc = t.length[len];
    const Code& dc = t.dist[d];
    bw.Put(lc.bits | (dc.bits << lc.len), lc.len + dc.len);
    rep = d;
    i += len;
    lit = i;
  }
  send_literals(n);
  bw.SetBit(block);  // the last block is the final one
  bw.Put(t.lit[256].bits, t.lit[256].len);  // end of block
  o = bw.Finish();
  const std::uint32_t adler = Adler32(1, in, n);
  *o++ = static_cast<unsigned char>(adler >> 24);
  *o++ = static_cast<unsigned char>(adler >> 16);
  *o++ = static_cast<unsigned char>(adler >> 8);
  *o++ = static_cast<unsigned char>(adler);
  return static_cast<size_t>(o - out);
}

void ShuffleDeflate(const unsigned char* in, size_t n, size_t elem, Bytes& scratch,
                    std::vector<unsigned char>& out) {
  out.resize(ZlibFixedBound(n));
  out.resize(ShuffleDeflate(in, n, elem, scratch, out.data()));
}

size_t ShuffleDeflate(const unsigned char* in, size_t n, size_t elem, Bytes& scratch,
                      unsigned char* out) {
  if (scratch.size() < n) scratch.resize(n);
  Shuffle(in, n, elem, scratch.data());
  return ZlibFixed(scratch.data(), n, out);
}

size_t ShuffleDeflatePadded(const unsigned char* in, size_t n, size_t chunk, size_t elem, Bytes& scratch,
                            unsigned char* out) {
  if (scratch.size() < chunk) scratch.resize(chunk);
  const size_t count = n / elem, stride = chunk / elem;
  // Each byte plane: the rows' bytes, then zeros up to the chunk's length.
  ShuffleInto(in, count, elem, scratch.data(), stride);
  for (size_t b = 0; b < elem; ++b) std::memset(scratch.data() + b * stride + count, 0, stride - count);
  return ZlibFixed(scratch.data(), chunk, out);
}

}  // namespace vibro::h5

// A whole chunk of a table, encoded as HDF5's shuffle and deflate filters decode it (docs/output.md,
// "Writing"): the elements' bytes transposed (byte 0 of every element, then byte 1, … as the shuffle
// filter), then a zlib stream (RFC 1950) of fixed-Huffman deflate blocks, with stored blocks for
// long runs of bytes that found no match (RFC 1951). Written
// with H5Dwrite_chunk, it is read back by any HDF5 reader exactly as a chunk that the library's own
// filters wrote; only the encoder differs: a greedy LZ77 search with one hash candidate and the
// last match's distance tried first (a periodic run's columns repeat every period), which skips
// ahead through bytes that do not repeat, and the fixed code, several times faster than zlib's
// level 1 on the store's columns (docs/performance.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <utility>
#include <vector>

namespace vibro::h5 {

// An allocator whose resize leaves new bytes as they come (no zero fill): the store's buffers are
// always written before they are read, and the zero fill of their growth was a few per cent of a
// stored run (docs/performance.md). Allocation failure still throws std::bad_alloc.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept {
    ::new (static_cast<void*>(p)) U;  // default-initialized: left as it is
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
using Bytes = std::vector<unsigned char, UninitializedAllocator<unsigned char>>;

// The byte transpose of HDF5's shuffle filter: n bytes of elements of `elem` bytes (n a multiple).
void Shuffle(const unsigned char* in, size_t n, size_t elem, unsigned char* out);
// The same for `count` elements into byte planes `stride` bytes apart (stride >= count): byte b of
// element i at out[b · stride + i]; the rest of each plane is left as it is.
void ShuffleInto(const unsigned char* in, size_t count, size_t elem, unsigned char* out, size_t stride);

// Adler-32 (RFC 1950) of n bytes, from `adler` (1 for a new stream).
std::uint32_t Adler32(std::uint32_t adler, const unsigned char* p, size_t n);
// Whether Adler32 takes its AVX2 path on this processor (asked once, at the first call).
bool Adler32UsesAvx2();

// The zlib stream of n bytes (header, fixed-Huffman and stored blocks, Adler-32) in `out` (resized).
void ZlibFixed(const unsigned char* in, size_t n, std::vector<unsigned char>& out);
// The most bytes ZlibFixed writes for n bytes.
size_t ZlibFixedBound(size_t n);
// The same stream written at `out` (ZlibFixedBound(n) bytes of room); returns its length.
size_t ZlibFixed(const unsigned char* in, size_t n, unsigned char* out);

// Shuffle then ZlibFixed: the bytes HDF5's shuffle + deflate filters read back as `in`.
// `scratch` holds the shuffled bytes (kept by the caller: no allocation per chunk).
void ShuffleDeflate(const unsigned char* in, size_t n, size_t elem, Bytes& scratch,
                    std::vector<unsigned char>& out);
// The same written at `out` (ZlibFixedBound(n) bytes of room, never cleared); returns its length.
size_t ShuffleDeflate(const unsigned char* in, size_t n, size_t elem, Bytes& scratch,
                      unsigned char* out);
// ShuffleDeflate of a chunk of `chunk` bytes whose first n are `in` and the rest zeros (HDF5's
// padding of an edge chunk), without a padded copy of the rows: the zeros are written in each byte
// plane of `scratch` (ZlibFixedBound(chunk) bytes of room at `out`).
size_t ShuffleDeflatePadded(const unsigned char* in, size_t n, size_t chunk, size_t elem, Bytes& scratch,
                            unsigned char* out);

}  // namespace vibro::h5

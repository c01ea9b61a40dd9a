// Wall selection's eight-lane loops (see wall_kernels.h), compiled for AVX2 alone (no -march flag).
#include "wall_kernels.h"

#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>

#include "lane8.h"
#define FPLOC_WALL_WIDE 1
#else
#define FPLOC_WALL_WIDE 0
#endif

#pragma GCC diagnostic ignored "-Wpsabi"

namespace fploc::seg::wallk {

#if FPLOC_WALL_WIDE
namespace {
using lane8::ld;
using lane8::st;
using lane8::v8f;
using lane8::v8i;
constexpr lane8::CompressTable<true> kCompress;
}  // namespace

namespace {
bool g_enabled = true;
}
bool available() { return g_enabled; }
void set_enabled(bool on) { g_enabled = on; }

__attribute__((target("avx2"))) size_t masks8(const float* x, const float* y, const float* z, int32_t a, int32_t b,
                                              const Bounds& bd, uint8_t* masks) {
  const v8f ncx = {bd.ncx, bd.ncx, bd.ncx, bd.ncx, bd.ncx, bd.ncx, bd.ncx, bd.ncx};
  const v8f ncy = {bd.ncy, bd.ncy, bd.ncy, bd.ncy, bd.ncy, bd.ncy, bd.ncy, bd.ncy};
  const v8f ncz = {bd.ncz, bd.ncz, bd.ncz, bd.ncz, bd.ncz, bd.ncz, bd.ncz, bd.ncz};
  const v8f mdc = {bd.mdc, bd.mdc, bd.mdc, bd.mdc, bd.mdc, bd.mdc, bd.mdc, bd.mdc};
  const v8f nfx = {bd.nfx, bd.nfx, bd.nfx, bd.nfx, bd.nfx, bd.nfx, bd.nfx, bd.nfx};
  const v8f nfy = {bd.nfy, bd.nfy, bd.nfy, bd.nfy, bd.nfy, bd.nfy, bd.nfy, bd.nfy};
  const v8f nfz = {bd.nfz, bd.nfz, bd.nfz, bd.nfz, bd.nfz, bd.nfz, bd.nfz, bd.nfz};
  const v8f mdf = {bd.mdf, bd.mdf, bd.mdf, bd.mdf, bd.mdf, bd.mdf, bd.mdf, bd.mdf};
  size_t cnt = 0, g = 0;
  for (int32_t j = a; j < b; j += 8) {
    const v8f px = ld(x + j), py = ld(y + j), pz = ld(z + j);
    const v8i in = (ncx * px + ncy * py + ncz * pz > mdc) & (nfx * px + nfy * py + nfz * pz > mdf);
    int mk = _mm256_movemask_ps(reinterpret_cast<__m256>(in));
    if (b - j < 8) mk &= (1 << (b - j)) - 1;
    masks[g++] = uint8_t(mk);
    cnt += size_t(__builtin_popcount(unsigned(mk)));
  }
  return cnt;
}

__attribute__((target("avx2"))) size_t copy8(const Source& s, int32_t a, int32_t b, int32_t row, int32_t off, int16_t u,
                                             const uint8_t* masks, const float* col_dt, const Measured* meas,
                                             const Out& out, size_t o) {
  // Every pointer in a register (restrict: the stores cannot change them, no reloads after each store).
  float* __restrict ox = out.x;
  float* __restrict oy = out.y;
  float* __restrict oz = out.z;
  float* __restrict orng = out.range;
  float* __restrict ot = out.t;
  int16_t* __restrict oring = out.ring;
  int16_t* __restrict ocol = out.col;
  const float* __restrict sx = s.x;
  const float* __restrict sy = s.y;
  const float* __restrict sz = s.z;
  const float* __restrict srange = s.range;
  const int32_t* __restrict spixel = s.pixel;
  const __m128i rings = _mm_set1_epi16(u);
  const __m256i iota = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m128i iota16 = _mm_setr_epi16(0, 1, 2, 3, 4, 5, 6, 7);
  // z from the range (s.zrow): fr = round(range * 1000) in float (Source)
  const bool zr = s.zrow != nullptr;
  const float zd = zr ? s.zrow[0] : 0.f, zo = zr ? s.zrow[1] : 0.f;
  const v8f zdv = {zd, zd, zd, zd, zd, zd, zd, zd}, zov = {zo, zo, zo, zo, zo, zo, zo, zo};
  const v8f k1000 = {1000.f, 1000.f, 1000.f, 1000.f, 1000.f, 1000.f, 1000.f, 1000.f};
#define z_of(rm) (zdv * reinterpret_cast<v8f>(_mm256_cvtepi32_ps(_mm256_cvtps_epi32(reinterpret_cast<__m256>((rm) * k1000)))) + zov)
  size_t g = 0;
  for (int32_t j = a; j < b; j += 8) {
    const int mk = masks[g++];
    if (mk == 0) continue;
    const int32_t pix0 = spixel[j];
    _mm_storeu_si128(reinterpret_cast<__m128i*>(oring + o), rings);
    if (mk == 255 && spixel[j + 7] == pix0 + 7) {  // eight neighbouring columns: blocks
      if (meas) {
        __m256i ri;
        std::memcpy(&ri, meas->range_mm + pix0, sizeof ri);
        const v8f fr = reinterpret_cast<v8f>(_mm256_cvtepi32_ps(ri));
        st(ox + o, ld(meas->lut[0] + pix0) * fr + ld(meas->lut[3] + pix0));
        st(oy + o, ld(meas->lut[1] + pix0) * fr + ld(meas->lut[4] + pix0));
        st(oz + o, ld(meas->lut[2] + pix0) * fr + ld(meas->lut[5] + pix0));
      } else {
        const v8f rm = ld(srange + j);
        st(ox + o, ld(sx + j));
        st(oy + o, ld(sy + j));
        st(oz + o, zr ? z_of(rm) : ld(sz + j));
        st(orng + o, rm);
      }
      if (meas) st(orng + o, ld(srange + j));
      st(ot + o, ld(col_dt + (pix0 - row)));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(ocol + o), _mm_add_epi16(_mm_set1_epi16(int16_t(pix0 + off)), iota16));
      o += 8;
      continue;
    }
    // Compress the set lanes to the front (the slots after them are overwritten by the next group).
    const __m256i idx = lane8::to_front(kCompress, mk);
    __m256i pix;
    std::memcpy(&pix, spixel + j, sizeof pix);
    pix = _mm256_permutevar8x32_epi32(pix, idx);
    const __m256i colv = _mm256_sub_epi32(pix, _mm256_set1_epi32(row));  // staggered column
    if (meas) {
      const __m256i rv = _mm256_i32gather_epi32(reinterpret_cast<const int*>(meas->range_mm), pix, 4);
      const v8f fr = reinterpret_cast<v8f>(_mm256_cvtepi32_ps(rv));
#define g8(p) reinterpret_cast<v8f>(_mm256_i32gather_ps((p), pix, 4))
      st(ox + o, g8(meas->lut[0]) * fr + g8(meas->lut[3]));
      st(oy + o, g8(meas->lut[1]) * fr + g8(meas->lut[4]));
      st(oz + o, g8(meas->lut[2]) * fr + g8(meas->lut[5]));
#undef g8
    } else {
      st(ox + o, reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(ld(sx + j)), idx)));
      st(oy + o, reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(ld(sy + j)), idx)));
    }
    const v8f qr = reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(ld(srange + j)), idx));
    if (!meas)
      st(oz + o, zr ? z_of(qr) : reinterpret_cast<v8f>(_mm256_permutevar8x32_ps(reinterpret_cast<__m256>(ld(sz + j)), idx)));
    st(orng + o, qr);
    st(ot + o, reinterpret_cast<v8f>(_mm256_i32gather_ps(col_dt, colv, 4)));
    const __m256i cd = _mm256_add_epi32(pix, _mm256_set1_epi32(off));
    const __m256i packed = _mm256_packs_epi32(cd, cd);  // per 128-bit half: c0..c3 c0..c3 | c4..c7 c4..c7
    const __m128i c16 = _mm_unpacklo_epi64(_mm256_castsi256_si128(packed), _mm256_extracti128_si256(packed, 1));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(ocol + o), c16);
    o += size_t(__builtin_popcount(unsigned(mk)));
    (void)iota;
  }
#undef z_of
  return o;
}
#else
bool available() { return false; }
void set_enabled(bool) {}
size_t masks8(const float*, const float*, const float*, int32_t, int32_t, const Bounds&, uint8_t*) { return 0; }
size_t copy8(const Source&, int32_t, int32_t, int32_t, int32_t, int16_t, const uint8_t*, const float*, const Measured*,
             const Out&, size_t o) {
  return o;
}
#endif

}  // namespace fploc::seg::wallk

#include "neraf/sim/rir_simulator.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <sstream>

#include "neraf/sim/scene_json.h"
#include "neraf/util/error.h"

namespace neraf::sim {

using geometry::Vec3;

namespace {

constexpr int kBands = 7;
using Bands = std::array<double, kBands>;
constexpr double kPi = geometry::kPi;
constexpr double kMinDistance = 0.1;    // 1/r is clamped below this distance (m)
constexpr double kMaxOcclusionDb = 25;  // single-edge diffraction loss cap
constexpr int kCoverageDirections = 512;

// ---------------------------------------------------------------------------------------------
// Small deterministic random numbers (splitmix64): identical on every platform and library.
struct SplitMix {
  uint64_t state;
  explicit SplitMix(uint64_t seed) : state(seed) {}
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return (next() >> 11) * (1.0 / 9007199254740992.0); }  // [0, 1)
  uint64_t below(uint64_t n) { return n ? next() % n : 0; }
};

uint64_t mix_hash(uint64_t h, uint64_t v) {
  SplitMix s(h ^ (v + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2)));
  return s.next();
}
uint64_t mix_hash(uint64_t h, double v) {
  v += 0.0;  // −0 → +0
  uint64_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return mix_hash(h, bits);
}

// ---------------------------------------------------------------------------------------------
// Octave filter bank: 6 crossovers at the geometric means of the band centres, each an order-4
// Butterworth low-pass / high-pass pair (two RBJ biquads, Q = 0.5412, 1.3066). Butterworth pairs
// are power complementary (|LP|² + |HP|² = 1), so the tree band_b = HP_0..HP_{b−1}·LP_b has Σ_b
// |band_b|² = 1: run forward-backward (zero phase, magnitude |band_b|²) the bands sum to an exact
// impulse; run forward only they split white noise into power-complementary bands.
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
};

Biquad rbj(bool highpass, double fs, double fc, double q) {
  const double w0 = 2 * kPi * fc / fs, c = std::cos(w0), alpha = std::sin(w0) / (2 * q);
  const double a0 = 1 + alpha;
  Biquad f;
  if (highpass) {
    f.b0 = (1 + c) / 2 / a0;
    f.b1 = -(1 + c) / a0;
  } else {
    f.b0 = (1 - c) / 2 / a0;
    f.b1 = (1 - c) / a0;
  }
  f.b2 = f.b0;
  f.a1 = -2 * c / a0;
  f.a2 = (1 - alpha) / a0;
  return f;
}

using Section4 = std::array<Biquad, 2>;  // an order-4 Butterworth low- or high-pass

struct Crossover {
  Section4 lp, hp;
};

Crossover make_crossover(double fs, double fc) {
  const double q1 = 1 / (2 * std::cos(kPi / 8)), q2 = 1 / (2 * std::cos(3 * kPi / 8));
  return {{rbj(false, fs, fc, q1), rbj(false, fs, fc, q2)},
          {rbj(true, fs, fc, q1), rbj(true, fs, fc, q2)}};
}

void biquad_forward(const Biquad& f, float* x, int n) {
  double s1 = 0, s2 = 0;  // transposed direct form II
  for (int i = 0; i < n; ++i) {
    const double in = x[i], y = f.b0 * in + s1;
    s1 = f.b1 * in - f.a1 * y + s2;
    s2 = f.b2 * in - f.a2 * y;
    x[i] = static_cast<float>(y);
  }
}

// Two independent order-4 sections run interleaved (the recursions are latency bound, so two
// chains in one loop cost about as much as one).
void section_pair(const Section4& fa, float* xa, const Section4& fb, float* xb, int n,
                  bool backward) {
  double s[2][2][2] = {};  // [signal][biquad][state]
  const Section4* f[2] = {&fa, &fb};
  float* x[2] = {xa, xb};
  for (int k = 0; k < n; ++k) {
    const int i = backward ? n - 1 - k : k;
    for (int c = 0; c < 2; ++c) {
      double v = x[c][i];
      for (int q = 0; q < 2; ++q) {
        const Biquad& b = (*f[c])[q];
        const double y = b.b0 * v + s[c][q][0];
        s[c][q][0] = b.b1 * v - b.a1 * y + s[c][q][1];
        s[c][q][1] = b.b2 * v - b.a2 * y;
        v = y;
      }
      x[c][i] = static_cast<float>(v);
    }
  }
}

void section_forward(const Section4& f, float* x, int n) {
  biquad_forward(f[0], x, n);
  biquad_forward(f[1], x, n);
}

// Squared magnitude of the order-4 digital Butterworth at normalised frequency (for the tiny-FFT
// diffuse-field average; bilinear transform: tan(ω/2) replaces the analog frequency).
double butter_power(bool highpass, double f, double fc, double fs) {
  const double r = std::tan(kPi * std::min(f, 0.4999 * fs) / fs) / std::tan(kPi * fc / fs);
  const double r8 = std::pow(r, 8);
  return highpass ? r8 / (1 + r8) : 1 / (1 + r8);
}

// In-place radix-2 complex FFT (constructor-only use: diffuse-field HRTF powers).
void fft_inplace(std::vector<std::complex<double>>& a) {
  const size_t n = a.size();
  for (size_t i = 1, j = 0; i < n; ++i) {
    size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (size_t len = 2; len <= n; len <<= 1) {
    const double ang = -2 * kPi / static_cast<double>(len);
    const std::complex<double> wl(std::cos(ang), std::sin(ang));
    for (size_t i = 0; i < n; i += len) {
      std::complex<double> w(1, 0);
      for (size_t k = 0; k < len / 2; ++k) {
        const auto u = a[i + k], v = a[i + k + len / 2] * w;
        a[i + k] = u + v;
        a[i + k + len / 2] = u - v;
        w *= wl;
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// ISO 9613-1 pure-tone air attenuation (dB/m) at 20 °C, 50 % relative humidity, 101.325 kPa.
double air_attenuation_db_per_m(double f) {
  const double t = 293.15, t0 = 293.15, t01 = 273.16, hr = 50;
  const double c_sat = -6.8346 * std::pow(t01 / t, 1.261) + 4.6151;
  const double h = hr * std::pow(10.0, c_sat);  // molar concentration of water vapour (%)
  const double fr_o = 24 + 4.04e4 * h * (0.02 + h) / (0.391 + h);
  const double fr_n =
      std::pow(t / t0, -0.5) * (9 + 280 * h * std::exp(-4.170 * (std::pow(t / t0, -1.0 / 3) - 1)));
  return 8.686 * f * f *
         (1.84e-11 * std::sqrt(t / t0) +
          std::pow(t / t0, -2.5) * (0.01275 * std::exp(-2239.1 / t) / (fr_o + f * f / fr_o) +
                                    0.1068 * std::exp(-3352.0 / t) / (fr_n + f * f / fr_n)));
}

std::string fmt_vec(const Vec3& v) {
  std::ostringstream s;
  s << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return s.str();
}

Vec3 forward_dir(double yaw_deg) {
  const double t = geometry::deg_to_rad(yaw_deg);
  return {-std::sin(t), 0, -std::cos(t)};
}

struct BoxGeom {
  Vec3 center, half;         // half sizes in the box frame
  Vec3 ex, ey{0, 1, 0}, ez;  // box axes in the world
  Bands refl{};              // specular reflection amplitude per band
  std::array<Vec3, 8> corners;
  bool on_floor = false;

  Vec3 axis(int a) const { return a == 0 ? ex : (a == 1 ? ey : ez); }
  Vec3 to_local(const Vec3& p) const {
    const Vec3 d = p - center;
    return {geometry::dot(d, ex), d.y, geometry::dot(d, ez)};
  }
  bool contains(const Vec3& p) const {
    const Vec3 l = to_local(p);
    return std::abs(l.x) <= half.x && std::abs(l.y) <= half.y && std::abs(l.z) <= half.z;
  }
  // Does the open segment p→q pass through the box interior? (slab test in the box frame)
  bool intersects(const Vec3& p, const Vec3& q) const {
    const Vec3 a = to_local(p), d = to_local(q) - a;
    double t0 = 1e-7, t1 = 1 - 1e-7;
    for (int k = 0; k < 3; ++k) {
      const double h = half[k] * (1 - 1e-9);
      if (std::abs(d[k]) < 1e-15) {
        if (std::abs(a[k]) >= h) return false;
        continue;
      }
      double lo = (-h - a[k]) / d[k], hi = (h - a[k]) / d[k];
      if (lo > hi) std::swap(lo, hi);
      t0 = std::max(t0, lo);
      t1 = std::min(t1, hi);
      if (t0 >= t1) return false;
    }
    return true;
  }
};

}  // namespace

// =============================================================================================
struct RirSimulator::Impl {
  RirSimOptions opt;
  const Hrtf* hrtf = nullptr;
  int fs = 0, len = 0, channels = 1, max_order = 0;
  double c = 343;
  Vec3 room;
  std::array<Bands, 6> wall_refl{};  // x0, x1, floor, ceiling, z0, z1
  // wall_pow[w][n][b] = wall_refl[w][b]^n for n ≤ max_order
  std::vector<Bands> wall_pow;
  Bands air_amp_np{};  // amplitude attenuation per metre (Np/m)
  std::vector<BoxGeom> boxes;
  Bands t60{};
  double volume = 0, area = 0, wall_scattering = 0;

  std::array<Crossover, kBands - 1> xo;

  // Receiver filters: fractional-delay kernels (mono) or fractional-delay ⊛ trimmed HRIR
  // (binaural). [n_dirs, ears, phases, filt_len]
  int n_dirs = 1, ears = 1, phases = 8, filt_len = 0, filt_centre = 0;
  double ref_offset = 0;  // samples between filter index filt_centre and the nominal arrival
  std::vector<float> table;

  // Late tail.
  int noise_span = 0;                    // valid offsets [0, noise_span)
  std::vector<float> noise;              // [7, noise_span + len]
  std::vector<float> tail_env;           // [7, len] sqrt(4πc/V · decay_b(t) / fs)
  std::vector<float> specular_fraction;  // [len] (1 − s̄)^(c t S / 4V)
  std::array<Bands, 2> ear_gain{};       // diffuse-field HRTF amplitude per ear and band
  Bands coherence{};
  std::vector<Vec3> coverage_dirs;

  size_t table_index(int dir, int ear, int phase) const {
    return ((static_cast<size_t>(dir) * ears + ear) * phases + phase) * filt_len;
  }

  void validate_point(const Vec3& p, const std::string& what) const {
    const double eps = 1e-9;
    require(geometry::is_finite(p) && p.x >= -eps && p.y >= -eps && p.z >= -eps &&
                p.x <= room.x + eps && p.y <= room.y + eps && p.z <= room.z + eps,
            what + " " + fmt_vec(p) + " lies outside the room [0, " + std::to_string(room.x) +
                "] x [0, " + std::to_string(room.y) + "] x [0, " + std::to_string(room.z) +
                "]; move it inside");
  }

  double directivity(const Source& s, const Vec3& departure) const {
    if (s.directivity == "omni") return 1.0;
    const double cosphi = geometry::dot(departure, forward_dir(s.yaw_deg));
    const double f = opt.cardioid_floor;
    return f + (1 - f) * (0.5 + 0.5 * cosphi);
  }
  double directivity_power(const Source& s) const {  // mean of D² over the sphere
    if (s.directivity == "omni") return 1.0;
    const double f = opt.cardioid_floor, a = f + (1 - f) / 2, b = (1 - f) / 2;
    return a * a + b * b / 3;
  }

  // Multiplies `gain` by the diffraction loss of every box the segment p→q crosses.
  bool occlude(const Vec3& p, const Vec3& q, int skip_box, Bands& gain) const {
    bool any = false;
    for (int i = 0; i < static_cast<int>(boxes.size()); ++i) {
      if (i == skip_box || !boxes[i].intersects(p, q)) continue;
      any = true;
      const double delta = detour(p, q, boxes[i]);
      for (int b = 0; b < kBands; ++b) {
        const double n = 2 * delta * kOctaveBandsHz[b] / c;
        const double x = std::sqrt(2 * kPi * n);
        const double il =
            std::min(kMaxOcclusionDb, 5 + (x > 1e-9 ? 20 * std::log10(x / std::tanh(x)) : 0.0));
        gain[b] *= std::pow(10.0, -il / 20);
      }
    }
    return any;
  }

  // Path-length difference of the cheapest way around `box` for the segment p→q: over/under/left/
  // right of the box's silhouette, the edge placed where the box centre projects on the segment.
  double detour(const Vec3& p, const Vec3& q, const BoxGeom& box) const {
    const double l = geometry::norm(q - p);
    if (l < 1e-9) return 0;
    const Vec3 u = (q - p) / l;
    Vec3 v1 = Vec3(0, 1, 0) - u * u.y;
    if (geometry::norm(v1) < 1e-3) v1 = Vec3(1, 0, 0) - u * u.x;
    v1 = geometry::normalized(v1);
    const Vec3 v2 = geometry::cross(u, v1);
    const double a = std::clamp(geometry::dot(box.center - p, u), 0.0, l), b = l - a;
    double best = -1, fallback = -1;
    for (const Vec3& v : {v1, -v1, v2, -v2}) {
      double h = 0;
      for (const Vec3& corner : box.corners) h = std::max(h, geometry::dot(corner - p, v));
      const double d = std::sqrt(a * a + h * h) + std::sqrt(b * b + h * h) - l;
      const Vec3 edge = p + u * a + v * h;
      const bool in_room = edge.x >= 0 && edge.y >= 0 && edge.z >= 0 && edge.x <= room.x &&
                           edge.y <= room.y && edge.z <= room.z;
      if (in_room && (best < 0 || d < best)) best = d;
      if (fallback < 0 || d < fallback) fallback = d;
    }
    return best >= 0 ? best : fallback;
  }

  static double fold(double x, int cell, double l) {
    const double local = x - cell * l;
    return (cell & 1) ? l - local : local;
  }

  void collect(const Source& src, const Vec3& mic, std::vector<Arrival>& out) const {
    out.clear();
    const int n = max_order;
    const Vec3 s = src.position;
    const bool occ = opt.furniture_occlusion && !boxes.empty();
    std::vector<double> ts;
    ts.reserve(n + 2);
    for (int kx = -n; kx <= n; ++kx) {
      const int ny = n - std::abs(kx);
      for (int ky = -ny; ky <= ny; ++ky) {
        const int nz = ny - std::abs(ky);
        for (int kz = -nz; kz <= nz; ++kz) {
          const int k[3] = {kx, ky, kz};
          Vec3 img;
          for (int a = 0; a < 3; ++a)
            img[a] = k[a] * room[a] + ((k[a] & 1) ? room[a] - s[a] : s[a]);
          const Vec3 d = img - mic;
          const double r = geometry::norm(d);
          Arrival arr;
          arr.distance_m = r;
          arr.delay_s = r / c;
          arr.order = std::abs(kx) + std::abs(ky) + std::abs(kz);
          arr.direction_world = r > 1e-12 ? d / r : Vec3(0, 0, -1);
          Vec3 dep = r > 1e-12 ? -d / r : Vec3(0, 0, -1);
          for (int a = 0; a < 3; ++a)
            if (k[a] & 1) dep[a] = -dep[a];
          const double base = directivity(src, dep) / std::max(r, kMinDistance);
          for (int b = 0; b < kBands; ++b) arr.gain[b] = base * std::exp(-air_amp_np[b] * r);
          for (int a = 0; a < 3; ++a) {
            if (k[a] == 0) continue;
            const int m = std::abs(k[a]);
            const int hi = k[a] > 0 ? (m + 1) / 2 : m / 2;  // hits of the wall at coordinate L
            const int lo = m - hi;                          // hits of the wall at 0
            const Bands& p_lo = wall_pow[(2 * a) * (n + 1) + lo];
            const Bands& p_hi = wall_pow[(2 * a + 1) * (n + 1) + hi];
            for (int b = 0; b < kBands; ++b) arr.gain[b] *= p_lo[b] * p_hi[b];
          }
          if (occ) {
            // Unfold: the straight line mic→image crosses the lattice planes; each piece, folded
            // back into the room, is one leg of the real path.
            ts.clear();
            for (int a = 0; a < 3; ++a) {
              if (k[a] == 0) continue;
              if (k[a] > 0)
                for (int j = 1; j <= k[a]; ++j) ts.push_back((j * room[a] - mic[a]) / d[a]);
              else
                for (int j = 0; j >= k[a] + 1; --j) ts.push_back((j * room[a] - mic[a]) / d[a]);
            }
            std::sort(ts.begin(), ts.end());
            ts.push_back(1.0);
            double t_prev = 0;
            for (double t : ts) {
              const Vec3 p0 = mic + d * t_prev, p1 = mic + d * t,
                         mid = mic + d * (0.5 * (t_prev + t));
              Vec3 f0, f1;
              for (int a = 0; a < 3; ++a) {
                const int cell = static_cast<int>(std::floor(mid[a] / room[a]));
                f0[a] = fold(p0[a], cell, room[a]);
                f1[a] = fold(p1[a], cell, room[a]);
              }
              if (t > t_prev + 1e-12) arr.occluded |= occlude(f0, f1, -1, arr.gain);
              t_prev = t;
            }
          }
          out.push_back(arr);
        }
      }
    }
    if (opt.furniture_reflections) add_furniture_reflections(src, mic, out);
    std::stable_sort(out.begin(), out.end(),
                     [](const Arrival& a, const Arrival& b) { return a.delay_s < b.delay_s; });
  }

  void add_furniture_reflections(const Source& src, const Vec3& mic,
                                 std::vector<Arrival>& out) const {
    const Vec3 s = src.position;
    for (int bi = 0; bi < static_cast<int>(boxes.size()); ++bi) {
      const BoxGeom& box = boxes[bi];
      for (int a = 0; a < 3; ++a) {
        for (int sign = -1; sign <= 1; sign += 2) {
          if (a == 1 && sign < 0 && box.on_floor) continue;
          const Vec3 nrm = box.axis(a) * sign;
          const Vec3 fc = box.center + nrm * box.half[a];
          const double ds = geometry::dot(s - fc, nrm), dm = geometry::dot(mic - fc, nrm);
          if (ds <= 1e-9 || dm <= 1e-9) continue;
          const Vec3 img = s - nrm * (2 * ds);
          const Vec3 d = img - mic;
          const double t = dm / (dm + ds);  // where mic→img crosses the face plane
          const Vec3 hit = mic + d * t;
          const int t1 = (a + 1) % 3, t2 = (a + 2) % 3;
          const Vec3 rel = hit - fc;
          if (std::abs(geometry::dot(rel, box.axis(t1))) > box.half[t1] ||
              std::abs(geometry::dot(rel, box.axis(t2))) > box.half[t2])
            continue;
          const double r = geometry::norm(d);
          Arrival arr;
          arr.distance_m = r;
          arr.delay_s = r / c;
          arr.order = 1;
          arr.furniture = true;
          arr.direction_world = geometry::normalized(hit - mic);
          const Vec3 dep = geometry::normalized(hit - s);
          const double base = directivity(src, dep) / std::max(r, kMinDistance);
          for (int b = 0; b < kBands; ++b)
            arr.gain[b] = base * std::exp(-air_amp_np[b] * r) * box.refl[b];
          if (opt.furniture_occlusion) {
            arr.occluded |= occlude(s, hit, bi, arr.gain);
            arr.occluded |= occlude(hit, mic, bi, arr.gain);
          }
          out.push_back(arr);
        }
      }
    }
  }

  // Distance from the mic, per fixed direction, at which the image lattice exceeds max_order
  // (the (max_order+1)-th plane crossing), sorted ascending.
  std::vector<double> coverage_radii(const Vec3& mic) const {
    std::vector<double> radii(coverage_dirs.size());
    for (size_t i = 0; i < coverage_dirs.size(); ++i) {
      const Vec3& u = coverage_dirs[i];
      double next[3], step[3];
      for (int a = 0; a < 3; ++a) {
        const double ua = std::abs(u[a]);
        if (ua < 1e-12) {
          next[a] = step[a] = std::numeric_limits<double>::infinity();
          continue;
        }
        next[a] = (u[a] > 0 ? room[a] - mic[a] : mic[a]) / ua;
        step[a] = room[a] / ua;
      }
      double r = 0;
      for (int crossing = 0; crossing <= max_order; ++crossing) {
        const int a =
            next[0] <= next[1] ? (next[0] <= next[2] ? 0 : 2) : (next[1] <= next[2] ? 1 : 2);
        r = next[a];
        next[a] += step[a];
      }
      radii[i] = r;
    }
    std::sort(radii.begin(), radii.end());
    return radii;
  }
};

// =============================================================================================
RirSimulator::RirSimulator(const Scene& scene, int sample_rate, const Hrtf* hrtf,
                           RirSimOptions options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.opt = options;
  m.hrtf = hrtf;
  m.fs = sample_rate;
  require(sample_rate >= 16000 && sample_rate <= 384000,
          "RIR sample rate " + std::to_string(sample_rate) +
              " Hz: the 8 kHz octave band needs at least 16000 Hz (and at most 384000)");
  const Acoustics& ac = scene.acoustics;
  require(std::isfinite(ac.speed_of_sound) && ac.speed_of_sound > 1,
          "the scene's acoustics.speed_of_sound must be a number of m/s above 1 (air: 343)");
  require(ac.max_order >= 0 && ac.max_order <= kMaxReflectionOrder,
          "the scene's acoustics.max_order must be in 0.." + std::to_string(kMaxReflectionOrder) +
              " (the image count grows as order³)");
  require(std::isfinite(ac.rir_length_s) && ac.rir_length_s > 0 && ac.rir_length_s <= 30,
          "the scene's acoustics.rir_length_s must be in (0, 30] seconds");
  require(
      geometry::is_finite(scene.size) && scene.size.x > 0 && scene.size.y > 0 && scene.size.z > 0,
      "the scene's size must be three positive numbers (metres)");
  require(options.frac_delay_taps >= 2 && options.frac_delay_taps % 2 == 0 &&
              options.frac_delay_taps <= 128,
          "RirSimOptions.frac_delay_taps must be even and in 2..128");
  require(options.frac_delay_phases >= 1 && options.frac_delay_phases <= 256,
          "RirSimOptions.frac_delay_phases must be in 1..256");
  require(options.hrir_max_taps >= 8, "RirSimOptions.hrir_max_taps must be at least 8");
  require(options.cardioid_floor >= 0 && options.cardioid_floor <= 1,
          "RirSimOptions.cardioid_floor must be in [0, 1]");
  if (options.binaural) {
    require(hrtf != nullptr,
            "binaural RIR simulation needs an HRTF (pass a loaded Hrtf or use mono)");
    require(hrtf->sample_rate() == sample_rate,
            hrtf->path() + ": HRTF loaded at " + std::to_string(hrtf->sample_rate()) +
                " Hz but the RIRs are simulated at " + std::to_string(sample_rate) +
                " Hz; load the Hrtf at the simulation rate");
  }
  m.c = ac.speed_of_sound;
  m.max_order = ac.max_order;
  m.room = scene.size;
  m.len = static_cast<int>(std::lround(ac.rir_length_s * sample_rate));
  require(m.len >= 1, "the scene's acoustics.rir_length_s is shorter than one sample");
  m.channels = options.binaural ? 2 : 1;

  // --- materials ---
  auto material = [&](const std::string& name, const std::string& where) -> const Material& {
    const auto it = scene.materials.find(name);
    require(it != scene.materials.end(), "scene.json: " + where + ": unknown material '" + name +
                                             "'; define it under \"materials\"");
    const Material& mat = it->second;
    for (double a : mat.absorption)
      require(std::isfinite(a) && a >= 0 && a <= 1,
              "scene.json: materials." + name + ".absorption: values must be in [0, 1]");
    require(std::isfinite(mat.scattering) && mat.scattering >= 0 && mat.scattering <= 1,
            "scene.json: materials." + name + ".scattering must be in [0, 1]");
    return mat;
  };
  auto refl = [](const Material& mat) {
    Bands r{};
    for (int b = 0; b < kBands; ++b)
      r[b] = std::sqrt(std::max(0.0, (1 - mat.absorption[b]) * (1 - mat.scattering)));
    return r;
  };
  const RoomSurfaces& su = scene.surfaces;
  const std::array<std::pair<std::string, std::string>, 6> wall_names = {
      {{su.wall_x0, "surfaces.wall_x0"},
       {su.wall_x1, "surfaces.wall_x1"},
       {su.floor, "surfaces.floor"},
       {su.ceiling, "surfaces.ceiling"},
       {su.wall_z0, "surfaces.wall_z0"},
       {su.wall_z1, "surfaces.wall_z1"}}};
  const Vec3 L = scene.size;
  const std::array<double, 6> wall_area = {L.y * L.z, L.y * L.z, L.x * L.z,
                                           L.x * L.z, L.x * L.y, L.x * L.y};
  std::array<double, 6> wall_area_eff = wall_area;
  Bands absorb_area{};  // Σ S_i α_i per band
  double area = 0, scat_area = 0, wall_area_total = 0;

  // --- furniture ---
  double furniture_volume = 0;
  struct FaceArea {
    double area;
    const Material* mat;
  };
  std::vector<FaceArea> furniture_faces;
  for (size_t i = 0; i < scene.furniture.size(); ++i) {
    const Box& bx = scene.furniture[i];
    const std::string where = "furniture[" + std::to_string(i) + "]";
    require(geometry::is_finite(bx.center) && std::isfinite(bx.yaw_deg),
            "scene.json: " + where + ": center and yaw_deg must be finite numbers");
    require(geometry::is_finite(bx.size) && bx.size.x > 0 && bx.size.y > 0 && bx.size.z > 0,
            "scene.json: " + where + ".size: must be three positive numbers");
    const Material& mat = material(bx.material, where + ".material");
    BoxGeom g;
    g.center = bx.center;
    g.half = bx.size * 0.5;
    const double t = geometry::deg_to_rad(bx.yaw_deg);
    // Rotation by yaw about +y (the same rotation that turns forward(0) into forward(yaw)).
    g.ex = Vec3(std::cos(t), 0, -std::sin(t));
    g.ez = Vec3(std::sin(t), 0, std::cos(t));
    g.refl = refl(mat);
    int ci = 0;
    for (int sx = -1; sx <= 1; sx += 2)
      for (int sy = -1; sy <= 1; sy += 2)
        for (int sz = -1; sz <= 1; sz += 2)
          g.corners[ci++] =
              g.center + g.ex * (sx * g.half.x) + g.ey * (sy * g.half.y) + g.ez * (sz * g.half.z);
    g.on_floor = bx.center.y - g.half.y <= 0.01;
    furniture_volume += bx.size.x * bx.size.y * bx.size.z;
    const double ax = bx.size.y * bx.size.z, ay = bx.size.x * bx.size.z, az = bx.size.x * bx.size.y;
    furniture_faces.push_back({2 * ax + 2 * az + (g.on_floor ? ay : 2 * ay), &mat});
    if (g.on_floor) wall_area_eff[2] = std::max(0.0, wall_area_eff[2] - ay);
    m.boxes.push_back(g);
  }

  for (int w = 0; w < 6; ++w) {
    const Material& mat = material(wall_names[w].first, wall_names[w].second);
    m.wall_refl[w] = refl(mat);
    area += wall_area_eff[w];
    for (int b = 0; b < kBands; ++b)
      absorb_area[b] += wall_area_eff[w] * std::min(mat.absorption[b], 0.999);
    scat_area += wall_area[w] * mat.scattering;
    wall_area_total += wall_area[w];
  }
  for (const FaceArea& f : furniture_faces) {
    area += f.area;
    for (int b = 0; b < kBands; ++b)
      absorb_area[b] += f.area * std::min(f.mat->absorption[b], 0.999);
  }
  m.wall_scattering = scat_area / wall_area_total;
  const double room_volume = L.x * L.y * L.z;
  m.volume = std::max(room_volume - furniture_volume, 0.2 * room_volume);
  m.area = area;
  m.wall_pow.assign(6 * (m.max_order + 1), Bands{});
  for (int w = 0; w < 6; ++w)
    for (int n = 0; n <= m.max_order; ++n)
      for (int b = 0; b < kBands; ++b)
        m.wall_pow[w * (m.max_order + 1) + n][b] = std::pow(m.wall_refl[w][b], n);

  // --- air absorption and Eyring ---
  for (int b = 0; b < kBands; ++b) {
    const double db_per_m =
        options.air_absorption ? air_attenuation_db_per_m(kOctaveBandsHz[b]) : 0.0;
    m.air_amp_np[b] = db_per_m / 8.686;
    const double alpha_mean = std::min(absorb_area[b] / area, 0.999);
    const double energy_air = 2 * m.air_amp_np[b];  // intensity attenuation per metre
    const double denom = m.c * (-area * std::log(1 - alpha_mean) + 4 * energy_air * m.volume);
    m.t60[b] = denom > 0 ? 24 * std::log(10.0) * m.volume / denom : 1e3;
  }

  // --- band filter bank ---
  for (int k = 0; k < kBands - 1; ++k)
    m.xo[k] = make_crossover(sample_rate, kOctaveBandsHz[k] * std::sqrt(2.0));

  // --- receiver filter table ---
  m.phases = options.frac_delay_phases;
  const int taps = options.frac_delay_taps;
  m.filt_centre = taps / 2 - 1;
  std::vector<std::vector<double>> kernels(m.phases, std::vector<double>(taps));
  for (int p = 0; p < m.phases; ++p) {
    const double mu = static_cast<double>(p) / m.phases;
    double sum = 0;
    for (int i = 0; i < taps; ++i) {
      const double x = i - m.filt_centre - mu;  // distance from the (fractional) peak
      const double sinc = std::abs(x) < 1e-12 ? 1.0 : std::sin(kPi * x) / (kPi * x);
      const double wx = x / (taps / 2.0);  // in (−1, 1]
      const double win =
          std::abs(wx) >= 1 ? 0.0 : 0.42 + 0.5 * std::cos(kPi * wx) + 0.08 * std::cos(2 * kPi * wx);
      kernels[p][i] = sinc * win;
      sum += kernels[p][i];
    }
    for (double& v : kernels[p]) v /= sum;  // unit DC gain
  }
  std::vector<std::vector<float>> hrirs;  // [dir*ears + ear] trimmed, truncated HRIRs
  if (options.binaural) {
    const int n = hrtf->filter_length();
    m.n_dirs = hrtf->num_directions();
    m.ears = 2;
    auto onset = [&](const float* ir) {
      float peak = 0;
      for (int i = 0; i < n; ++i) peak = std::max(peak, std::abs(ir[i]));
      int i = 0;
      while (i < n - 1 && std::abs(ir[i]) < 0.1f * peak) ++i;
      return i;
    };
    int min_onset = n;
    for (int d = 0; d < m.n_dirs; ++d)
      for (int e = 0; e < 2; ++e) min_onset = std::min(min_onset, onset(hrtf->ir(d, e)));
    const int guard = std::max(2, static_cast<int>(std::lround(1e-4 * sample_rate)));
    const int trim = std::max(0, min_onset - guard);
    const int front = hrtf->nearest_index(Vec3(1, 0, 0));
    m.ref_offset = 0.5 * (onset(hrtf->ir(front, 0)) + onset(hrtf->ir(front, 1))) - trim;
    const int keep = std::min(options.hrir_max_taps, n - trim);
    const int fade = std::max(1, keep / 8);
    hrirs.assign(m.n_dirs * 2, std::vector<float>(keep));
    for (int d = 0; d < m.n_dirs; ++d)
      for (int e = 0; e < 2; ++e) {
        const float* ir = hrtf->ir(d, e) + trim;
        std::vector<float>& h = hrirs[d * 2 + e];
        for (int i = 0; i < keep; ++i) {
          const int from_end = keep - 1 - i;
          const double w =
              from_end >= fade ? 1.0 : 0.5 - 0.5 * std::cos(kPi * (from_end + 0.5) / fade);
          h[i] = static_cast<float>(ir[i] * w);
        }
      }
  } else {
    hrirs.assign(1, std::vector<float>(1, 1.0f));
  }
  const int hlen = static_cast<int>(hrirs[0].size());
  m.filt_len = (taps + hlen - 1 + 7) / 8 * 8;
  m.table.assign(static_cast<size_t>(m.n_dirs) * m.ears * m.phases * m.filt_len, 0.0f);
  for (int d = 0; d < m.n_dirs; ++d)
    for (int e = 0; e < m.ears; ++e)
      for (int p = 0; p < m.phases; ++p) {
        float* f = m.table.data() + m.table_index(d, e, p);
        const std::vector<float>& h = hrirs[d * m.ears + e];
        for (int i = 0; i < taps; ++i)
          for (int j = 0; j < hlen; ++j) f[i + j] += static_cast<float>(kernels[p][i] * h[j]);
      }

  // --- late tail ---
  if (options.late_tail) {
    const int len = m.len;
    m.noise_span = std::max(1 << 15, 2 * len);
    const int total = m.noise_span + len;
    const int warmup = static_cast<int>(0.1 * sample_rate);
    m.noise.assign(static_cast<size_t>(kBands) * total, 0.0f);
    SplitMix rng(0x5EEDF00Dull);  // fixed: the tables are part of the model, not of the seed
    std::vector<float> white(total + warmup), impulse(static_cast<size_t>(0.2 * sample_rate), 0.0f);
    for (int b = 0; b < kBands; ++b) {
      for (size_t i = 0; i < white.size(); i += 2) {  // Box–Muller
        const double u1 = 1.0 - rng.uniform(), u2 = rng.uniform();
        const double rad = std::sqrt(-2 * std::log(u1));
        white[i] = static_cast<float>(rad * std::cos(2 * kPi * u2));
        if (i + 1 < white.size()) white[i + 1] = static_cast<float>(rad * std::sin(2 * kPi * u2));
      }
      std::fill(impulse.begin(), impulse.end(), 0.0f);
      impulse[0] = 1;
      auto band_filter = [&](float* x, int n) {
        for (int k = 0; k < b; ++k) section_forward(m.xo[k].hp, x, n);
        if (b < kBands - 1) section_forward(m.xo[b].lp, x, n);
      };
      band_filter(white.data(), static_cast<int>(white.size()));
      band_filter(impulse.data(), static_cast<int>(impulse.size()));
      double target = 0, actual = 0;  // variance of unit white noise through the band filter
      for (float v : impulse) target += double(v) * v;
      for (int i = 0; i < total; ++i) actual += double(white[warmup + i]) * white[warmup + i];
      actual /= total;
      const double scale = actual > 0 ? std::sqrt(target / actual) : 0.0;
      for (int i = 0; i < total; ++i)
        m.noise[static_cast<size_t>(b) * total + i] = static_cast<float>(white[warmup + i] * scale);
    }
    m.tail_env.assign(static_cast<size_t>(kBands) * len, 0.0f);
    m.specular_fraction.assign(len, 0.0f);
    const double density = 4 * kPi * m.c / m.volume;
    const double reflections_per_s = m.c * m.area / (4 * m.volume);
    for (int i = 0; i < len; ++i) {
      const double t = static_cast<double>(i) / sample_rate;
      for (int b = 0; b < kBands; ++b)
        m.tail_env[static_cast<size_t>(b) * len + i] = static_cast<float>(
            std::sqrt(density * std::exp(-13.815510557964274 * t / m.t60[b]) / sample_rate));
      m.specular_fraction[i] =
          static_cast<float>(std::pow(1 - m.wall_scattering, reflections_per_s * t));
    }
    // Fibonacci sphere: fixed, evenly spread directions for the image-coverage estimate.
    m.coverage_dirs.resize(kCoverageDirections);
    const double golden = kPi * (3 - std::sqrt(5.0));
    for (int i = 0; i < kCoverageDirections; ++i) {
      const double z = 1 - (i + 0.5) * 2.0 / kCoverageDirections, rr = std::sqrt(1 - z * z);
      m.coverage_dirs[i] = Vec3(rr * std::cos(golden * i), z, rr * std::sin(golden * i));
    }
    for (int b = 0; b < kBands; ++b) {
      const double x = 2 * kPi * kOctaveBandsHz[b] * options.head_diameter_m / m.c;
      m.coherence[b] = options.binaural ? std::sin(x) / x : 1.0;
    }
    // Diffuse-field HRTF power per ear and band: direction average of |H|² weighted by the band's
    // |band_b(f)|², relative to the band's own power.
    for (auto& g : m.ear_gain) g.fill(1.0);
    if (options.binaural) {
      int nfft = 1;
      while (nfft < 2 * hlen) nfft <<= 1;
      nfft = std::max(nfft, 1024);
      std::vector<double> mean_power(2 * (nfft / 2 + 1), 0.0);
      std::vector<std::complex<double>> buf(nfft);
      for (int d = 0; d < m.n_dirs; ++d)
        for (int e = 0; e < 2; ++e) {
          std::fill(buf.begin(), buf.end(), 0.0);
          const std::vector<float>& h = hrirs[d * 2 + e];
          for (int i = 0; i < hlen; ++i) buf[i] = h[i];
          fft_inplace(buf);
          for (int k = 0; k <= nfft / 2; ++k)
            mean_power[e * (nfft / 2 + 1) + k] += std::norm(buf[k]) / m.n_dirs;
        }
      for (int b = 0; b < kBands; ++b) {
        double wsum = 0, pw[2] = {0, 0};
        for (int k = 0; k <= nfft / 2; ++k) {
          const double f = static_cast<double>(k) * sample_rate / nfft;
          double w = 1;
          for (int j = 0; j < b; ++j)
            w *= butter_power(true, f, kOctaveBandsHz[j] * std::sqrt(2.0), sample_rate);
          if (b < kBands - 1)
            w *= butter_power(false, f, kOctaveBandsHz[b] * std::sqrt(2.0), sample_rate);
          wsum += w;
          for (int e = 0; e < 2; ++e) pw[e] += w * mean_power[e * (nfft / 2 + 1) + k];
        }
        for (int e = 0; e < 2; ++e) m.ear_gain[e][b] = wsum > 0 ? std::sqrt(pw[e] / wsum) : 0.0;
      }
    }
  }
}

RirSimulator::~RirSimulator() = default;

std::vector<Arrival> RirSimulator::arrivals(const Source& source, const Vec3& mic_position) const {
  const Impl& m = *impl_;
  m.validate_point(source.position, "source");
  m.validate_point(mic_position, "microphone");
  require(source.directivity == "omni" || source.directivity == "cardioid",
          "source directivity '" + source.directivity + "': use \"omni\" or \"cardioid\"");
  std::vector<Arrival> out;
  m.collect(source, mic_position, out);
  return out;
}

std::vector<std::vector<float>> RirSimulator::render(const Source& source, const Vec3& mic_position,
                                                     double mic_yaw_deg) const {
  const Impl& m = *impl_;
  require(std::isfinite(mic_yaw_deg) && std::isfinite(source.yaw_deg),
          "microphone/source yaw must be a finite number of degrees");
  const std::vector<Arrival> arr = arrivals(source, mic_position);
  const int len = m.len, ears = m.ears;
  std::vector<std::vector<float>> out(ears, std::vector<float>(len, 0.0f));

  // ---- early part: per-band, per-ear sparse accumulation, then the zero-phase band merge ----
  const int pad = static_cast<int>(std::ceil(0.03 * m.fs));  // IIR ringing room on both sides
  double max_pos = 0;
  for (const Arrival& a : arr) max_pos = std::max(max_pos, a.delay_s * m.fs);
  const int early =
      static_cast<int>(std::min<double>(std::ceil(max_pos) + m.filt_len + 8, len + 8.0));
  const int n_buf = pad + early + pad;
  std::vector<float> bands(static_cast<size_t>(ears) * kBands * n_buf, 0.0f);
  auto band_buf = [&](int ear, int b) {
    return bands.data() + (static_cast<size_t>(ear) * kBands + b) * n_buf;
  };
  for (const Arrival& a : arr) {
    int dir = 0;
    if (m.ears == 2)
      dir = m.hrtf->nearest_index(Hrtf::world_to_head(a.direction_world, mic_yaw_deg));
    for (int ear = 0; ear < ears; ++ear) {
      double pos = a.delay_s * m.fs - m.ref_offset;
      if (m.ears == 2) pos += m.hrtf->delay_s(dir, ear) * m.fs;
      double whole = std::floor(pos);
      int phase = static_cast<int>(std::lround((pos - whole) * m.phases));
      if (phase == m.phases) {
        phase = 0;
        whole += 1;
      }
      const long start = pad + static_cast<long>(whole) - m.filt_centre;
      if (start >= n_buf || start + m.filt_len <= 0) continue;
      const float* f = m.table.data() + m.table_index(dir, ear, phase);
      const int i0 = static_cast<int>(std::max<long>(0, -start));
      const int i1 = static_cast<int>(std::min<long>(m.filt_len, n_buf - start));
      for (int b = 0; b < kBands; ++b) {
        const float g = static_cast<float>(a.gain[b]);
        if (g == 0.0f) continue;
        float* dst = band_buf(ear, b) + start;
        for (int i = i0; i < i1; ++i) dst[i] += g * f[i];
      }
    }
  }
  // Σ_b band_b(y_b) = LP0~y0 + HP0~(LP1~y1 + HP1~(… + HP5~y6)), "~" = forward-backward.
  for (int ear = 0; ear < ears; ++ear) {
    float* z = band_buf(ear, kBands - 1);
    for (int k = kBands - 2; k >= 0; --k) {
      float* y = band_buf(ear, k);
      section_pair(m.xo[k].lp, y, m.xo[k].hp, z, n_buf, false);
      section_pair(m.xo[k].lp, y, m.xo[k].hp, z, n_buf, true);
      for (int i = 0; i < n_buf; ++i) y[i] += z[i];
      z = y;
    }
    const int n_copy = std::min(len, n_buf - pad);
    std::copy(z + pad, z + pad + n_copy, out[ear].begin());
  }

  // ---- late diffuse tail ----
  if (m.opt.late_tail) {
    uint64_t h = mix_hash(m.opt.seed, uint64_t{0x7A11});
    for (int a = 0; a < 3; ++a) h = mix_hash(h, source.position[a]);
    h = mix_hash(h, source.directivity == "omni" ? 0.0 : source.yaw_deg);
    for (int a = 0; a < 3; ++a) h = mix_hash(h, mic_position[a]);
    if (m.ears == 2) h = mix_hash(h, mic_yaw_deg);
    SplitMix rng(h);

    const int t_direct =
        static_cast<int>(std::ceil(geometry::norm(source.position - mic_position) / m.c * m.fs));
    if (t_direct < len) {
      // q(t) = sqrt(1 − C(ct)·S(t)): the share of the diffuse-field energy not rendered as images.
      const std::vector<double> radii = m.coverage_radii(mic_position);
      std::vector<float> q(len - t_direct);
      size_t covered_idx = 0;  // radii[0..covered_idx) are < r
      const double n_dirs = static_cast<double>(radii.size());
      for (int i = t_direct; i < len; ++i) {
        const double r = m.c * i / m.fs;
        while (covered_idx < radii.size() && radii[covered_idx] < r) ++covered_idx;
        const double coverage = (n_dirs - covered_idx) / n_dirs;
        q[i - t_direct] =
            static_cast<float>(std::sqrt(std::max(0.0, 1 - coverage * m.specular_fraction[i])));
      }
      const double p_dir = std::sqrt(m.directivity_power(source));
      const int total = m.noise_span + len;
      for (int b = 0; b < kBands; ++b) {
        const uint64_t span = static_cast<uint64_t>(m.noise_span);
        const uint64_t o_left = rng.below(span);
        const uint64_t o_right = (o_left + span / 4 + rng.below(span / 2)) % span;
        const float sign_left = (rng.next() & 1) ? 1.0f : -1.0f;
        const float sign_right = (rng.next() & 1) ? 1.0f : -1.0f;
        const float* tab = m.noise.data() + static_cast<size_t>(b) * total;
        const float* env = m.tail_env.data() + static_cast<size_t>(b) * len;
        const float* nl = tab + o_left;
        const float* nr = tab + o_right;
        const int n = len - t_direct;
        const float* qq = q.data();
        {
          const float g = static_cast<float>(p_dir * m.ear_gain[0][b]) * sign_left;
          float* dst = out[0].data() + t_direct;
          const float* e = env + t_direct;
          const float* x = nl + t_direct;
          for (int i = 0; i < n; ++i) dst[i] += g * qq[i] * e[i] * x[i];
        }
        if (ears == 2) {
          const double rho = m.coherence[b];
          const float gc = static_cast<float>(p_dir * m.ear_gain[1][b] * rho) * sign_left;
          const float gi = static_cast<float>(p_dir * m.ear_gain[1][b] *
                                              std::sqrt(std::max(0.0, 1 - rho * rho))) *
                           sign_right;
          float* dst = out[1].data() + t_direct;
          const float* e = env + t_direct;
          const float* x = nl + t_direct;
          const float* y = nr + t_direct;
          for (int i = 0; i < n; ++i) dst[i] += qq[i] * e[i] * (gc * x[i] + gi * y[i]);
        }
      }
    }
  }
  return out;
}

std::array<double, 7> RirSimulator::eyring_t60() const { return impl_->t60; }
int RirSimulator::sample_rate() const { return impl_->fs; }
int RirSimulator::channels() const { return impl_->ears; }
int RirSimulator::length_samples() const { return impl_->len; }
bool RirSimulator::inside_furniture(const Vec3& p) const {
  for (const BoxGeom& b : impl_->boxes)
    if (b.contains(p)) return true;
  return false;
}

}  // namespace neraf::sim

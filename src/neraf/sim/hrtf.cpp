#include "neraf/sim/hrtf.h"

#include <mysofa.h>

#include <algorithm>
#include <cmath>
#include <fstream>

#include "neraf/util/error.h"

namespace neraf::sim {

using geometry::Vec3;

namespace {

std::string mysofa_error_text(int err) {
  switch (err) {
    case MYSOFA_INVALID_FORMAT:
      return "not a valid SOFA/HDF5 file";
    case MYSOFA_UNSUPPORTED_FORMAT:
      return "unsupported SOFA convention or layout";
    case MYSOFA_NO_MEMORY:
      return "out of memory";
    case MYSOFA_READ_ERROR:
      return "read error";
    case MYSOFA_INVALID_ATTRIBUTES:
      return "invalid SOFA attributes";
    case MYSOFA_INVALID_DIMENSIONS:
      return "invalid SOFA dimensions";
    case MYSOFA_INVALID_DIMENSION_LIST:
      return "invalid SOFA dimension list";
    case MYSOFA_INVALID_COORDINATE_TYPE:
      return "invalid SOFA coordinate type";
    case MYSOFA_ONLY_EMITTER_WITH_ECI_SUPPORTED:
      return "only one emitter is supported";
    case MYSOFA_ONLY_DELAYS_WITH_IR_OR_MR_SUPPORTED:
      return "unsupported Data.Delay layout";
    case MYSOFA_ONLY_THE_SAME_SAMPLING_RATE_SUPPORTED:
      return "mixed sampling rates";
    case MYSOFA_RECEIVERS_WITH_RCI_SUPPORTED:
      return "unsupported receiver layout";
    case MYSOFA_RECEIVERS_WITH_CARTESIAN_SUPPORTED:
      return "receivers must be cartesian";
    case MYSOFA_INVALID_RECEIVER_POSITIONS:
      return "invalid receiver positions (need left +y, right -y)";
    case MYSOFA_ONLY_SOURCES_WITH_MC_SUPPORTED:
      return "unsupported source position layout";
    default:
      return "libmysofa error " + std::to_string(err);
  }
}

}  // namespace

Hrtf::Hrtf(int sample_rate, const std::string& sofa_path)
    : sample_rate_(sample_rate), path_(sofa_path) {
  require(sample_rate >= 8000 && sample_rate <= 384000,
          sofa_path + ": HRTF sample rate " + std::to_string(sample_rate) +
              " Hz is out of range; use 8000..384000 Hz");
  {
    std::ifstream probe(sofa_path, std::ios::binary);
    require(probe.good(), sofa_path +
                              ": cannot open the SOFA HRTF file; install libmysofa-dev's "
                              "data (default.sofa) or pass an existing .sofa file");
  }
  int filter_length = 0, err = 0;
  // mysofa_open resamples to `sample_rate`, normalises the loudness and converts positions to
  // cartesian coordinates. Its lookup state (easy->fir) is not thread-safe, so every measurement is
  // copied out here and libmysofa is closed again.
  MYSOFA_EASY* easy =
      mysofa_open(sofa_path.c_str(), static_cast<float>(sample_rate), &filter_length, &err);
  if (!easy || err != MYSOFA_OK) {
    if (easy) mysofa_close(easy);
    throw Error(sofa_path + ": cannot read the SOFA HRTF (" + mysofa_error_text(err) +
                "); use a SimpleFreeFieldHRIR .sofa file such as " + kDefaultSofa);
  }
  const MYSOFA_HRTF* h = easy->hrtf;
  const int m_count = static_cast<int>(h->M), n = static_cast<int>(h->N);
  if (h->R != 2 || h->C != 3 || m_count < 1 || n < 1 || n != filter_length) {
    mysofa_close(easy);
    throw Error(sofa_path + ": expected a 2-receiver (binaural) HRIR set with cartesian positions");
  }
  filter_length_ = n;
  directions_.resize(m_count);
  irs_.assign(h->DataIR.values, h->DataIR.values + static_cast<size_t>(m_count) * 2 * n);
  delays_s_.assign(static_cast<size_t>(m_count) * 2, 0.0);
  for (int m = 0; m < m_count; ++m) {
    const float* p = h->SourcePosition.values + 3 * m;
    directions_[m] = geometry::normalized(Vec3(p[0], p[1], p[2]));
  }
  // Data.Delay is in samples at the (resampled) rate: either one pair for all measurements [1, R]
  // or one pair per measurement [M, R].
  const unsigned delay_elements = h->DataDelay.elements;
  if (h->DataDelay.values && (delay_elements == 2 || delay_elements == 2u * h->M)) {
    for (int m = 0; m < m_count; ++m)
      for (int ear = 0; ear < 2; ++ear) {
        const size_t i = delay_elements == 2 ? ear : 2 * m + ear;
        delays_s_[2 * m + ear] = h->DataDelay.values[i] / static_cast<double>(sample_rate);
      }
  }
  mysofa_close(easy);
  for (float v : irs_)
    if (!std::isfinite(v)) throw Error(sofa_path + ": the HRIRs contain NaN/Inf values");
}

Hrtf::~Hrtf() = default;

int Hrtf::nearest_index(const Vec3& direction_head) const {
  Vec3 d = geometry::normalized(direction_head);
  if (!(geometry::norm(d) > 0) || !geometry::is_finite(d)) d = Vec3(1, 0, 0);
  int best = 0;
  double best_dot = -2;
  for (int m = 0; m < static_cast<int>(directions_.size()); ++m) {
    const double c = geometry::dot(directions_[m], d);
    if (c > best_dot) {
      best_dot = c;
      best = m;
    }
  }
  return best;
}

const float* Hrtf::ir(int index, int ear) const {
  return irs_.data() + (static_cast<size_t>(index) * 2 + ear) * filter_length_;
}

void Hrtf::lookup(const Vec3& direction_head, std::vector<float>& left, std::vector<float>& right,
                  double& left_delay_s, double& right_delay_s) const {
  const int m = nearest_index(direction_head);
  left.assign(ir(m, 0), ir(m, 0) + filter_length_);
  right.assign(ir(m, 1), ir(m, 1) + filter_length_);
  left_delay_s = delays_s_[2 * m];
  right_delay_s = delays_s_[2 * m + 1];
}

Vec3 Hrtf::world_to_head(const Vec3& v, double yaw_deg) {
  // scene.h: forward(θ) = (−sin θ, 0, −cos θ); left = forward(θ + 90°) = (−cos θ, 0, sin θ); up =
  // +y.
  const double t = geometry::deg_to_rad(yaw_deg);
  const Vec3 forward(-std::sin(t), 0, -std::cos(t));
  const Vec3 left(-std::cos(t), 0, std::sin(t));
  return {geometry::dot(v, forward), geometry::dot(v, left), v.y};
}

}  // namespace neraf::sim

#pragma once
// Real spherical-harmonics direction encoding with tiny-cuda-nn's `SphericalHarmonics` sign
// convention (degree = number of bands; output dims = degree²). Nerfacto uses degree 4 → 16 dims.
//
// Input mapping: tcnn expects v ∈ [0,1]³ and evaluates the polynomials on 2v − 1. nerfstudio feeds
// it (d + 1)/2 for a unit direction d, so the net effect is SH of d itself: use sh_encode(d).
// NeRAF's orientation encoding stores ((cosθ+1)/2, 0.5, (sinθ+1)/2) and feeds that to tcnn: use
// sh_encode_tcnn_input(v), which is sh_encode(2v − 1).
//
// Polynomials (x, y, z of the unit vector), in output order:
//   Y0 = 0.28209479                    Y1 = −0.48860251·y          Y2 = 0.48860251·z
//   Y3 = −0.48860251·x                 Y4 = 1.0925484·xy           Y5 = −1.0925484·yz
//   Y6 = 0.94617470·z² − 0.31539157    Y7 = −1.0925484·xz          Y8 = 0.54627422·(x² − y²)
//   Y9 = 0.59004359·y(−3x² + y²)       Y10 = 2.8906114·xyz         Y11 = 0.45704580·y(1 − 5z²)
//   Y12 = 0.37317633·z(5z² − 3)        Y13 = 0.45704580·x(1 − 5z²) Y14 = 1.4453057·z(x² − y²)
//   Y15 = 0.59004359·x(−x² + 3y²)
// The inputs are not renormalised (as in tcnn): pass unit vectors.
#include <torch/types.h>

#include <cstdint>

namespace neraf::nerf {

// dirs: [N, 3] unit vectors (float32 or float64, any device) → [N, degree²], same dtype/device.
// degree ∈ {1, 2, 3, 4}. Differentiable w.r.t. dirs (camera-optimizer gradients flow through it).
// On CPU a custom op (one pass forward, analytic backward); elsewhere sh_encode_reference.
torch::Tensor sh_encode(const torch::Tensor& dirs, int degree = 4);

// The same polynomials as plain tensor ops (autograd for the gradient): the tests' reference and
// the non-CPU path.
torch::Tensor sh_encode_reference(const torch::Tensor& dirs, int degree = 4);

// v: [N, 3] in tcnn's [0,1]³ input space → sh_encode(2v − 1, degree).
torch::Tensor sh_encode_tcnn_input(const torch::Tensor& v, int degree = 4);

// Raw CPU kernels behind sh_encode (row-major; deterministic for any num_threads).
// out: [n, degree²]; grad_dirs: [n, 3], overwritten with Σ_k grad_out[:, k] · ∂Y_k/∂dir.
template <typename T>
void sh_forward_cpu(const T* dirs, int64_t n, int degree, T* out, int num_threads);
template <typename T>
void sh_backward_cpu(const T* dirs, int64_t n, int degree, const T* grad_out, T* grad_dirs,
                     int num_threads);

}  // namespace neraf::nerf

#pragma once
// A spatial upscaler in the style of AMD FidelityFX Super Resolution 1.0, written from the public
// description of the algorithm (the "FSR" row of Table 1 in the CGSR paper):
//   EASU: edge-adaptive spatial upsampling. Per output pixel, 12 input taps around the sample
//         point; the local gradient direction and an edge "length" (how much the gradient
//         reverses across the four nearest texels) shape an anisotropic, Lanczos-2-like kernel
//         stretched along the edge; the result is clamped to the four nearest texels (no ringing).
//   RCAS: robust contrast-adaptive sharpening. A 5-tap cross whose negative lobe is limited so
//         that it never pushes a pixel outside the range of its neighbours.
// Input and output are display-referred colour in [0,1] (FSR expects perceptual space); values
// outside [0,1] are clamped first. RCAS is FSR 1.0's default configuration: its compile-time
// noise-removal variant (off by default there, for grainy content) is left out on purpose.
// fsr1_easu and upscale_fsr1 reject NaN/Inf input (cgsr::Error). fsr1_rcas does not check: a NaN
// texel turns its 5-texel cross NaN (in its own channel, maybe in the others) and nothing else.
// CPU only; float and double are computed in their own precision, half and bfloat16 in float.

#include <torch/types.h>

namespace cgsr {

struct Fsr1Options {
  double sharpness_stops = 0.2;  // RCAS: 0 = strongest; each stop halves the sharpening
  bool sharpen = true;           // run RCAS after EASU
};

torch::Tensor fsr1_easu(const torch::Tensor& lr, int scale);
torch::Tensor fsr1_rcas(const torch::Tensor& image, double sharpness_stops);
torch::Tensor upscale_fsr1(const torch::Tensor& lr, int scale, const Fsr1Options& options = {});

}  // namespace cgsr

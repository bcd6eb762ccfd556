#pragma once
/// LDR-FLIP: the perceptual difference of two images a viewer flips between, after Andersson,
/// Nilsson, Akenine-Möller, Oskarsson, Åström and Fairchild, "FLIP: A Difference Evaluator for
/// Alternating Images", Proc. ACM Comput. Graph. Interact. Tech. 3(2), 2020 (HPG 2020), §3–4.
/// Written from the paper.
///
/// Per pixel, an error in [0, 1] from two parts:
///  - colour (§4.1): both images are filtered by the eye's contrast sensitivity for the
///    achromatic, red–green and blue–yellow channels (Gaussians in degrees of visual angle, so the
///    viewing distance sets their width in pixels), taken to CIELAB with the Hunt effect, and
///    compared by the HyAB distance, compressed and remapped so that 0.95 is where differences
///    become obvious;
///  - features (§4.2): edges and points of the luminance, by the first and second derivatives of a
///    Gaussian; where one image has an edge or a point the other lacks, the colour error is raised.
///
/// The pipeline is split in two, so that compare can match a pixel of one image against what the
/// other holds near it (its alignment, cli/image_metrics.hpp).

#include <array>
#include <vector>

namespace softbake {

/// How the images are seen: pixels per degree of visual angle. The paper's default, a 0.7 m wide
/// 3840-pixel monitor seen from 0.7 m, gives 67.0.
struct FlipViewing {
  double pixelsPerDegree = 0.7 * 3840 / 0.7 * 3.14159265358979323846 / 180;
};

/// One pixel as FLIP compares it: the Hunt-adjusted L*a*b* of the filtered colours (L, 0.01·L·a,
/// 0.01·L·b), then the magnitudes of the luminance's edge response (|∇|, by the first derivative
/// of a Gaussian) and point response (|(∂²x, ∂²y)|).
using FlipPixel = std::array<float, 5>;

/// `rgb`: 3 floats per pixel, rows top to bottom, sRGB-encoded values in [0, 1] (an LDR image as
/// shown). Returns its pixels as FLIP compares them, in the same order.
std::vector<FlipPixel> flipFeatures(const std::vector<float>& rgb, int width, int height,
                                    const FlipViewing& viewing = {});

/// The FLIP error between a reference pixel and a test pixel, in [0, 1]. Symmetric.
float flipError(const FlipPixel& reference, const FlipPixel& test);

}  // namespace softbake

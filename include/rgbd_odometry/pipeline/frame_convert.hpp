#pragma once
// What every source does to a sensor's images before the pipeline sees them (RgbdFrame):
// colour to intensity and depth readings to metres, on the SIMD kernels (simd/image.hpp):
// on the Odroid, Debian's OpenCV would run them without NEON. The grey values are OpenCV's
// cvtColor's, so replays of recordings and live frames agree with each other and with
// earlier versions.
#include <opencv2/core/mat.hpp>

namespace rgbdo {

// colour: CV_8UC3, blue first (OpenCV's imread) or red first (OpenNI2's RGB888) -> CV_8UC1.
void colour_to_gray(const cv::Mat& colour, bool red_first, cv::Mat& gray);

// raw: CV_16UC1 sensor units -> CV_32FC1 metres (0 stays 0: no reading).
void depth_to_metres(const cv::Mat& raw, double metres_per_unit, cv::Mat& metres);

}  // namespace rgbdo

#pragma once
namespace rgbdo {
inline constexpr const char* kVersion = "0.1.0";
}

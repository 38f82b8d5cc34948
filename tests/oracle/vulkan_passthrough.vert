#version 450
// The Vulkan oracle's only shader stage (tests/oracle/vulkan_device.cpp): clip-space positions are
// computed on the CPU (raster/transform.h), so the GPU sees the very floats the emulator sees.
layout(location = 0) in vec4 position;
void main() { gl_Position = position; }

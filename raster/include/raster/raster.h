// raster/raster.h: cullide's depth-only software rasterizer and occlusion-query emulator.
//
// It reproduces, bit for bit, what OpenGL on Mesa's llvmpipe (OSMesa 22.3.6, x86-64 host with FMA)
// writes into a depth buffer and counts in GL_SAMPLES_PASSED queries, for depth-only drawing of
// indexed triangles given in clip space. Every rule below was pinned by an experiment against that
// oracle (docs/conventions.md, "Rasterization (GL-exact mode)", names the experiment for each);
// tests/raster/conformance_test.cpp re-checks them on random scenes. With RasterRules::Vulkan (per
// batch) it reproduces Vulkan on Mesa's lavapipe the same way (below).
//
// Conventions of the default rules, RasterRules::GlLlvmpipe (GL names throughout; "window" = GL window
// coordinates, y up); the Vulkan rules follow below:
//  - Target: DepthTarget, width x height pixels, 1 <= width, height <= kMaxTargetSize. Pixel (x, y)
//    covers [x, x+1) x [y, y+1); row 0 is the bottom row (glReadPixels order). Formats D16, D24
//    (unsigned normalized, stored in the low 16/24 bits of a uint32) and D32F (float bits).
//  - Input: clip-space float4 vertices (x, y, z, w) and uint32 indices, three per triangle, in the
//    GL_TRIANGLES order. Clip volume -w <= x, y, z <= w; GL default depth range [0, 1]; no depth
//    clamp. Triangles crossing the volume are clipped against all six planes in clip space
//    (llvmpipe runs without a guard band), in the plane order +x, -x, +y, -y, near, far.
//  - Viewport (glViewport): x_w = (x/w) * (width/2) + (x0 + width/2), computed as llvmpipe does:
//    1/w first, then one fused multiply-add; z_w = (z/w) * 0.5 + 0.5 the same way. Pixels outside
//    the target are never touched; pixels outside a smaller viewport only by rounding, as in GL.
//  - Sampling: one sample at each pixel centre (x + 0.5, y + 0.5). Vertices are snapped to 1/256
//    pixel (16.8 fixed point, round half to even, after subtracting the 0.5 centre offset).
//  - Fill rule: a centre on an edge belongs to the triangle for left edges and bottom horizontal
//    edges only (llvmpipe's GL rule); shared edges are watertight. Zero-area triangles (in 16.8
//    fixed point) produce nothing.
//  - Facing: counter-clockwise in window coordinates (positive fixed-point area) is front when
//    FrontFace::CCW. Culling uses the snapped area, as llvmpipe does.
//  - Depth: a plane through the three float window positions, evaluated at the centre as
//    fma(dzdy, y, fma(dzdx, x, z0)) in float, clamped to [0, 1] and converted: D16 via the
//    float magic-number path, D24 as round-half-even(z * 16777215.0f), D32F unchanged.
//  - Depth test: DepthFunc compares the incoming value (left) with the stored one (right); the
//    stored value is replaced only when the test passes and the write mask is on.
//  - Queries: samples_passed counts samples that pass the depth test (mask on or off); any-samples
//    is samples_passed > 0. Queries do not nest (one active at a time), as with one GL target.
//  - Limits: kMaxTargetSize = 16384 per side, so 16.8 coordinates need at most 23 bits and edge
//    products fit in 64 bits (2^23 * 2^23 * 2).
//  - Errors: non-finite coordinates, indices out of range, index counts not a multiple of 3,
//    zero-size or oversized targets or viewports, unbalanced queries and a batch built for another
//    target size are rejected before anything is drawn; the target is then unchanged.
//  - Determinism: same input, same bits, for the scalar reference and the tiled path with any
//    thread count. Depth is computed from the plane at each pixel, never accumulated.
//
// Vulkan rules (RasterRules::Vulkan, chosen per CommandBatch; the above is RasterRules::GlLlvmpipe).
// They reproduce, bit for bit, Mesa's lavapipe 22.3.6 (the Vulkan driver on llvmpipe's rasterizer)
// with a depth-only render pass, one sample, VkViewport{x, y, width, height, 0, 1}, depthClampEnable
// off, no depth bias; tests/raster/vulkan_conformance_test.cpp re-checks them. What changes:
//  - Framebuffer: y grows downward in Vulkan's words, and row 0 (framebuffer y = 0, the top) is the
//    same memory row as GL's bottom row 0: the viewport formula x_f = (x/w) * (width/2) + (x0 +
//    width/2), likewise y, is GL's, so a batch means the same pixels under both rules.
//  - Clip volume: -w <= x, y <= w and 0 <= z <= w (near plane z >= 0, clip_halfz); clipped in clip
//    space in the same plane order, the same Sutherland-Hodgman.
//  - Depth mapping: z_w = (z/w) * 1 + 0 (maxDepth - minDepth, minDepth), fused as for x and y: no
//    scale and bias, so window depth is NDC depth.
//  - Sampling and fill rule: the same pixel centres (+0.5), 16.8 snapping and edge ties. Vulkan's
//    top-left rule on its y-down framebuffer is GL's left-and-bottom rule on the y-up reading of the
//    same memory (the horizontal tie edge is the one at the low end of y in both); 8 sub-pixel bits
//    (lavapipe's subPixelPrecisionBits).
//  - Facing: FrontFace::CCW means VK_FRONT_FACE_COUNTER_CLOCKWISE, counter-clockwise on the y-down
//    framebuffer, which is clockwise in GL's y-up reading: the opposite triangles of GL's CCW.
//  - Provoking vertex first (lavapipe's flatshade_first): where llvmpipe reorders a clockwise
//    triangle it swaps vertices 1 and 2 (GL: 0 and 1), and a clipped polygon's fan puts the
//    polygon's first vertex first (GL: last). Both change the depth plane's operation order, so the
//    depth values differ in the last bits, not the coverage.
//  - Depth clamp to [0, 1], conversions (D16, D24 = X8_D24_UNORM_PACK32, D32F), depth test and
//    precise occlusion queries (VK_QUERY_CONTROL_PRECISE_BIT counts) are GL's. clear(depth) stores
//    what vkCmdClearDepthStencilImage stores for the float `depth` (D16/D24: the GL rounding of it).
// RasterMode::ExactBounds draws follow GL's conventions whatever the batch's rules (they are
// conservative and emulator-only: no API to match).
//
// A second raster mode, RasterMode::ExactBounds (conservative: every pixel whose closed square the
// closed triangle meets, with [zmin, zmax] over the pixel, rounded outward; writes use zmin, queries
// zmax), is selected per draw through DrawState::mode: docs/reliable-raster.md. The paper's offset
// construction for the GL-exact mode is in raster/offset_geometry.h.
#pragma once

#include "raster/command_batch.h"
#include "raster/depth_target.h"
#include "raster/offset_geometry.h"
#include "raster/result.h"
#include "raster/transform.h"
#include "raster/types.h"

// The void-surface objective of Voronoi best-next-view sampling (Wilson 2002,
// ch. 3: §3.1.3, §3.2.1.2 and §3.4.2): the solid angle of view directions from
// a candidate eye point that see into space no existing sample has seen.
//
// The thesis renders per-sample void surfaces (skin triangles) with a stencil
// count; here the same quantity comes from space carving over the samples'
// depth cube maps, with no triangles: a point is known free when some sample
// sees past it, and a ray that leaves the union of the samples' free space
// other than through a sampled surface has met the void surface.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "stages/cube_map.h"
#include "stages/geometry.h"

namespace cellbake {

// One existing sample: its eye and six depth faces (stages/cube_map.h
// conventions: planar view depth per pixel, +inf = background, row 0 at the
// top, s = 2 (i + 0.5) / N - 1, t = 1 - 2 (j + 0.5) / N). Colours are not read.
struct VoidSample {
  const CubeSample* cube = nullptr;
};

struct VoidParams {
  // Rays per candidate: face_size^2 per cube face, through the pixel centres
  // of a cube map at the candidate.
  int face_size = 24;
  double step_ratio = 0.03;      // geometric marching: t_{k+1} = t_k * (1 + step_ratio)
  double start_distance = 0.05;  // first marching distance from the candidate (model units)
  // Rays still undecided this far are seen (background). 0 = the samples'
  // own extent (see void_fraction).
  double max_distance = 0;
  // Relative: a point whose planar depth z in a sample is within
  // surface_tolerance * z of that sample's stored depth lies on its surface.
  double surface_tolerance = 0.03;
  // Relative: stored depths at the two ends of a step through a sample's
  // surface that differ by more than jump * (the smaller) are a depth
  // discontinuity (a skin), not a surface.
  double jump = 0.1;
};

struct VoidResult {
  double fraction = 0;  // void solid angle / 4 pi, in [0, 1]
  std::size_t void_rays = 0, rays = 0;
  std::size_t marched_rays = 0;  // rays marched (the rest a VoidRayMemory knew as seen)
};

// What void_fraction learned at one candidate, for a later call there with
// more samples (best-next-view scores the same Voronoi vertices again after
// each new sample): the rays it found seen. A seen ray stays seen when samples
// are appended: before the step that decided it, the same samples certify
// every point (so no point is void), and at that step the same sample still
// meets a surface (rules 1, 2), the march still ends (rule 4), or the sample
// that sees only background along the rest of the ray still certifies all of
// it (rule 4's shortcut is exact: see there). Void rays are marched again.
struct VoidRayMemory {
  Vec3d candidate;
  VoidParams params;
  std::vector<Vec3d> eyes;                  // of the samples it was learned with, in order
  double max_distance = 0;                  // the march's last distance it was learned with
  std::vector<std::uint8_t> seen_for_good;  // per ray, in void_fraction's ray order
};

// The fraction of the sphere of view directions at `candidate` that sees the
// void surface of `samples`.
//
// Rays: the pixel centres of a cube map of face_size^2 pixels per face at the
// candidate (rays = 6 * face_size^2), each weighted by the exact solid angle of
// its pixel (about (2 / face_size)^2 / (1 + s^2 + t^2)^(3/2); the pixels tile
// the sphere), so `fraction` is the void solid angle over 4 pi.
//
// Marching: points X at distances t_0 = start_distance, t_{k+1} = t_k (1 +
// step_ratio), clamped to the last distance max_distance. X projects into
// sample k's cube map (face = dominant axis of X - eye_k, ties to x then y;
// the pixel containing the direction, i.e. the nearest pixel centre) with
// planar depth z and stored depth D there. X is *certified free* by k when
// z < D (background D = +inf certifies; X at eye_k is certified). At each
// point, in this order:
//  1. SEEN if X lies on a surface of some sample: D finite and |z - D| <= surface_tolerance * z;
//  2. SEEN if the step into X crossed a surface of some sample k: X was
//     certified by k at the previous point and is not now, and the two stored
//     depths agree within `jump` (a real surface; otherwise it passed behind a
//     silhouette into k's shadow, through a skin);
//  3. VOID if no sample certifies X (the ray is behind every sample's surfaces
//     without having met a sampled surface; this includes a ray that starts,
//     at start_distance, uncertified and not on a surface);
//  4. SEEN once X is at max_distance, or when every sample sees background at
//     X and one of them (each tried at most once per ray) sees only
//     background along the rest of the ray (its projection, a segment on each
//     face it crosses, walked pixel by pixel with the neighbours whose border
//     it passes within a thousandth of a pixel, and faces whose frustum it
//     misses by a hair, so that no rounding of the projection can reach an
//     unread pixel; rays passing within 1e-6 of the coordinates' magnitude of
//     that sample's eye are not tried): that sample certifies every later
//     point, so the ray can no longer become void (a shortcut for rays into
//     the sky; it does not change the outcome).
// max_distance = 0 means max_k (|candidate - eye_k| + 2 * largest finite depth
// of sample k), beyond which no sampled geometry lies (Euclidean distance <=
// sqrt(3) * planar depth); samples with only background contribute
// |candidate - eye_k|.
//
// Faces of one sample must have one size (samples may differ). Deterministic;
// the order of `samples` does not matter. O(rays * steps * samples) in
// time, O(samples + face_size^2) in memory; steps near the candidate that no
// sample can decide (a ball around it, per sample, seen as wholly free or
// wholly hidden by that sample's depths) are skipped without changing the
// outcome. With max_distance = 0 every depth of every sample is read once.
// Throws std::invalid_argument for no samples, a null cube, faces of differing
// sizes or with depth arrays of the wrong length, a non-finite candidate or
// eye, or bad params (face_size < 1, step_ratio, start_distance not finite
// and > 0, max_distance, surface_tolerance, jump not finite and >= 0).
VoidResult void_fraction(const Vec3d& candidate, std::span<const VoidSample> samples,
                         const VoidParams& params);

// The same result, bit for bit, marching only the rays `memory` does not know
// as seen, and updating it. `memory` must be empty (default-constructed) or
// come from calls at this candidate with these params whose samples were the
// first memory.eyes.size() of `samples` (the same cubes, appended to since);
// it is restarted when the march's last distance changed (max_distance = 0
// and a sample extended it). Throws std::invalid_argument as void_fraction,
// and for a memory of another candidate, other params or another sample
// prefix (eyes compared).
VoidResult void_fraction(const Vec3d& candidate, std::span<const VoidSample> samples,
                         const VoidParams& params, VoidRayMemory& memory);

}  // namespace cellbake

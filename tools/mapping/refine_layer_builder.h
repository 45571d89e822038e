// Offline (host, may use the heap): the map's refinement layer (core/include/gsf/detail/refine_layer.h)
// from full-precision points: sorted into the grid's tiles and cells, positions quantised in their cell,
// a normal per point from the PCA of the (quantised) points in its 27 surrounding cells.
#pragma once
#include <cstdint>
#include <vector>

#include "gsf/detail/refine_layer.h"
#include "gsf/status.h"

namespace gsf::mapping {

// xyz: n x 3 map-local points; cell: the grid's cell (m, the localizer's refine.cell). Points of one
// cell keep their input order. InvalidInput for a non-finite point, one beyond the tile key range
// (+-2^19 cells from the origin) or a tile whose points span 256 or more cells in z.
Status build_refine_layer(const float* xyz, uint32_t n, float cell, std::vector<MapRefineTile>* tiles,
                          std::vector<MapRefinePoint>* points);
// The same from the points in chunks (x, y, z each; the chunks in order), each chunk freed as soon as
// its points are placed, so the float points and the layer are not held whole at once. *chunks is
// empty afterwards.
Status build_refine_layer(std::vector<std::vector<float>>* chunks, float cell, std::vector<MapRefineTile>* tiles,
                          std::vector<MapRefinePoint>* points);

}  // namespace gsf::mapping

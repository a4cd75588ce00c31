#pragma once
// Topology tolerance (issue #35; not in Bertram et al. 2000): removes the
// handles, tunnels, specks and bubbles of an isosurface that are smaller than
// T cells, by changing a few samples of the field and nothing else, so that
// the base mesh (Sec. 4.1), which must keep the surface's topology, can be
// small. Every other sample keeps its value bit for bit, so every other part
// of the surface stays exactly where it was.
//
// The sample connectivity is exactly that of contour_volume(): inside
// samples are joined by grid edges and by the face diagonals the asymptotic
// decider connects, outside samples by grid edges and the other face
// diagonals, and no side by cell diagonals. In it:
// - Specks and bubbles: a component of the inside (outside) samples that does
//   not touch the volume box and whose crossings span less than T cells along
//   every axis changes side as a whole.
// - Handles and tunnels (weakest link): a sample off the box whose change of
//   side splits its side locally into two or more pieces while the other side
//   stays one piece around it, and whose neck is thin (2 pi times the mean
//   distance from the sample to its crossings, in cells, under T), is a thin
//   connection. All thin connections of a side (pairwise at least two samples
//   apart) are taken out, the rest is joined by union-find, and they are put
//   back strongest first; one whose pieces all reach each other without it
//   would only close cycles and stays cut (Kruskal's maximum spanning
//   forest). So each
//   cut removes a handle at its thinnest one-sample neck, nothing is ever
//   split or merged, and only necks thinner than T are cut. Inside handles
//   are cut first, then outside ones (tunnels) are filled, each side once:
//   a neck left out for spacing stays.
// Handles whose necks are more than one sample thick everywhere are kept.
//
// A changed sample gets its value mirrored through the isovalue (2 iso - v,
// at least one float step across; non-finite outside samples get iso), so
// the crossings around it move by less than a cell.
#include <cstddef>

#include "isowave/core/volume.h"

namespace isowave {

struct TopologyCleanup {
  std::size_t specks_removed = 0;   // inside components under T across, removed
  std::size_t bubbles_filled = 0;   // outside components under T across, filled
  std::size_t handles_cut = 0;      // inside necks cut (each removes one handle)
  std::size_t tunnels_filled = 0;   // outside necks filled (each removes one tunnel)
  std::size_t samples_changed = 0;  // samples whose value changed
  double seconds = 0;               // wall time of the clean-up
  bool changed() const { return samples_changed > 0; }
};

// Applies the tolerance `cells` (T) to `field` at `iso` in place. T = 0 does
// nothing. Throws Error(InvalidArgument) for a negative or non-finite T or a
// non-finite iso and Error(Unsupported) for 2^32 samples or more. Volumes
// under 3 samples along an axis are left alone. Cost: a 27-sample test per
// sample next to the surface and a union-find over the samples per side
// (both parallel over slabs), about the contouring's time;
// memory 6 bytes per sample. Deterministic for any thread count.
TopologyCleanup clean_topology(Volume& field, double iso, double cells);

}  // namespace isowave

#pragma once
// The side bench_surface_error, bench_fit_rate_distortion and
// bench_rate_distortion share (issues #33, #34): their options, each fit's
// whole `convert` in a forked child, Draco as a subprocess, and the surfaces
// D is measured between: the marching-cubes mesh of the field and the
// reference, the marching-cubes mesh of a 2x trilinear upsample of the
// field (2n - 1 samples per axis, spacing halved, same origin; the same
// extractor and isovalue), closer to the true isosurface than any coder's
// output. With --smooth the field is the pre-filtered one, as for the fit.
// With --topology-tolerance both stay those of the field before the clean-up:
// D is measured against the isosurface the user had.
// With --min-component-vertices the reference leaves out its faces in the
// cells (of the input grid) where the marching-cubes mesh has faces of
// dropped components only: the upsample keeps the field's samples, so its
// surface crosses the cells the coarse one does, while a vertex-count rule
// would not match (about 4x the vertices per component, and blobs that merge
// or split at the finer sampling).
//
// D is surface_error() (core/surface_error.h): area-uniform samples on both
// surfaces, RMS distance each way, D the larger; printed in % of a cell.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "isowave/codec/statistics.h"
#include "isowave/core/mesh.h"
#include "isowave/core/surface_error.h"
#include "isowave/extract/isosurface.h"
#include "isowave/pipeline/convert.h"

namespace isowave::bench {

struct BenchOptions {
  std::string input;          // a volume file or builtin:NAME[:N]
  IsosurfaceOptions extract;  // iso, min_component_vertices, smooth_sigma
  int levels = 0;             // 0: automatic
  // --flips: the simplifier's valence flips (off in convert).
  bool valence_flips = BaseMeshOptions{}.simplify.valence_flips;
  std::vector<FitMethod> fits{FitMethod::ShrinkWrap, FitMethod::Parametrization};
  // The children's ConvertOptions::summary_percents (FitOutcome::summary).
  std::vector<double> summary_percents{100, 20, 10, 5};
};

// The options the programs take (VOLUME --iso V [--levels N]
// [--min-component-vertices N] [--smooth S] [--topology-tolerance T] [--flips] [--fit ...]);
// anything else prints the usage under `program`'s name and exits with 2.
// `defaults` holds what the program does without an option (e.g. its fits);
// `extra_usage` ends the usage line (the program's own options, which it
// takes out of argv before).
BenchOptions parse_options(int argc, char** argv, const char* program, BenchOptions defaults = {},
                           const char* extra_usage = "");

const char* fit_name(FitMethod fit);

// What a child reports.
enum class FitStatus : std::int32_t { Done, NotAvailable, Failed };
struct FitFigures {
  std::int32_t levels = 0;
  std::uint64_t base_vertices = 0, fine_vertices = 0;
  double folded_share = 0, simplify_seconds = 0, distance_seconds = 0, fit_seconds = 0, convert_seconds = 0;
};

struct FitOutcome {
  FitStatus status = FitStatus::Failed;
  std::string message;  // unless Done
  FitFigures figures;
  double peak_megabytes = 0;  // the child's ru_maxrss: one whole convert
  PolygonMesh fine;           // the fitted fine control mesh (before quantization)
  std::string file;           // the .isw bytes
  std::vector<RateDistortionRow> summary;  // one row per BenchOptions::summary_percents, then the base mesh
};

// Runs `convert` (convert_volume with the CLI's defaults, a fit whose faces
// mostly fold kept) in a forked child that loads the volume itself and sends
// its outcome back through a pipe. Call it before this process touches TBB.
FitOutcome fit_in_child(const BenchOptions& o, FitMethod fit);

struct Surfaces {
  double cell = 1;  // the field's cell size (world units)
  PolygonMesh marching_cubes, reference;
  // With a topology tolerance: the marching-cubes mesh after it, and the
  // reference of the surface it keeps (2x upsample of the cleaned field).
  PolygonMesh tolerant, kept_reference;
};

// The marching-cubes mesh of the (pre-filtered) field and the reference from
// its 2x upsample; prints their sizes.
Surfaces extract_surfaces(const BenchOptions& o);

// What both programs start with: each of o.fits run by fit_in_child() (before
// anything touches TBB), the surfaces, and D of the marching-cubes mesh
// against the reference (printed).
struct FitRuns {
  std::vector<FitOutcome> outcomes;  // one per o.fits
  Surfaces surfaces;
  double marching_cubes_d = 0;       // world units
  double kept_marching_cubes_d = 0;  // the tolerant mesh against the kept reference (0: no tolerance)
};
FitRuns run_fits(const BenchOptions& o);

// Prints one row of D figures in % of `cell` under `what`; returns them.
SurfaceError print_error(const char* what, const PolygonMesh& mesh, const PolygonMesh& against, double cell);

// Prints a fit's figures and D of its fitted fine mesh against the reference
// and the marching-cubes mesh, with the target (D <= 1.25 x D of the
// marching-cubes mesh, or 1% of a cell where that is larger); false when the
// fit did not run (the line says why).
bool print_fit(FitMethod fit, const FitOutcome& outcome, const Surfaces& s, double marching_cubes_d,
               double kept_marching_cubes_d = 0);

// Draco, the peer, on one mesh: draco_encoder and draco_decoder run
// as subprocesses (output discarded) on the mesh written as PLY.
struct DracoCoded {
  std::uint64_t bytes = 0;  // the .drc file
  PolygonMesh decoded;      // what draco_decoder wrote
  double encode_seconds = 0, decode_seconds = 0;  // wall clock of each subprocess
};

class DracoCoder {
 public:
  // Both tools on PATH.
  static bool available();
  // Writes `mesh` as PLY into a fresh temporary directory, removed by the
  // destructor. Throws std::runtime_error if the directory cannot be made.
  explicit DracoCoder(const PolygonMesh& mesh);
  ~DracoCoder();
  DracoCoder(const DracoCoder&) = delete;
  DracoCoder& operator=(const DracoCoder&) = delete;

  // Encodes with `-qp quantization_bits -cl level` and decodes; nothing when
  // either tool fails (a line says so).
  std::optional<DracoCoded> code(int quantization_bits, int level) const;

 private:
  std::string directory_;
};

}  // namespace isowave::bench

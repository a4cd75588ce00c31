// The surface error D of the fits (issue #33, item 5): for one volume and
// isovalue, D at full resolution (the fitted fine control mesh, before
// quantization) of each fit and of the plain marching-cubes mesh, against the
// marching-cubes mesh of a 2x trilinear upsample of the field (the reference
// and the measure: surface_bench.h). The target: D(fit) <= 1.25 x
// D(marching cubes) against the reference, or <= 1% of a cell where that is
// larger.
//
// Each fit runs `convert` (convert_volume with the CLI's defaults, a fit
// whose faces mostly fold kept) in a forked child that loads the volume
// itself, so its peak memory (the child's ru_maxrss) is that of one whole
// convert; the children run before this process touches TBB, and send back
// the fine mesh and their figures through a pipe.
//
// usage: bench_surface_error VOLUME --iso V [--levels N] [--min-component-vertices N] [--smooth S] [--topology-tolerance T]
//                            [--fit shrink-wrap|parametrization|normal|both|all]
//   VOLUME is a file or builtin:NAME[:N]; --levels 0 (default) picks them
//   automatically; --fit defaults to both.
#include <cstdio>
#include <exception>

#include "surface_bench.h"

using namespace isowave;
using namespace isowave::bench;

int main(int argc, char** argv) {
  const BenchOptions o = parse_options(argc, argv, "bench_surface_error");
  try {
    const FitRuns runs = run_fits(o);
    for (std::size_t i = 0; i < o.fits.size(); ++i)
      print_fit(o.fits[i], runs.outcomes[i], runs.surfaces, runs.marching_cubes_d, runs.kept_marching_cubes_d);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_surface_error: %s\n", e.what());
    return 1;
  }
  return 0;
}

#pragma once
// Volume reader options shared by the subcommands that read volumes (extract,
// fit and convert): --dims, --type, --endian, --spacing, --origin, --field
// and --grid, turned into isowave::VolumeReadOptions; and the extraction and
// fit options those subcommands share.
#include <string>
#include <vector>

#include "cli.h"
#include "console_progress.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/extract/volume_summary.h"
#include "isowave/fit/shrink_wrap.h"

namespace isowave::cli {

// Appends the reader options to a command's option list.
void add_volume_options(std::vector<OptionSpec>& options);

// The reader options given on the command line; Error(InvalidArgument) for a
// malformed value (e.g. --dims 0,4,4, --spacing 1,x,1, --endian middle).
VolumeReadOptions volume_read_options(const Arguments& args);

// Appends the extraction options shared by extract, fit and convert:
// --min-component-vertices, --smooth and --flip.
void add_extraction_options(std::vector<OptionSpec>& options);

// Those options as given (iso left at 0); Error(InvalidArgument) for a
// --smooth outside 0..100 voxels.
IsosurfaceOptions extraction_options(const Arguments& args);

// One line on what the topology tolerance changed ("" when it was off), for
// extract and convert.
std::string topology_tolerance_line(const IsosurfaceReport& report);
// The same as a JSON object.
std::string topology_tolerance_json(const IsosurfaceReport& report);

// Appends --unfold-limit PERCENT (the fit command) and applies it to the
// shrink-wrap options: the unfold runs when untangle() left at most that
// share of the finest level's faces folded (0: never); Error(InvalidArgument)
// outside 0..100.
void add_unfold_option(std::vector<OptionSpec>& options);
void set_unfold_limit(const Arguments& args, ShrinkWrapOptions& options);

// What a command prints once a volume is loaded (see report_loaded_volume).
enum class LoadReport { RangeAndWarnings, WarningsOnly, Nothing };

// Prints "INPUT: values LOW .. HIGH, N NaN, M Inf" on stdout (RangeAndWarnings)
// and each of value_warnings() on stderr as "isowave COMMAND: warning: INPUT:
// ..." (unless Nothing), so that a misread file is caught before the work.
// With `progress`, the range goes into the run's progress report and the
// warnings through it (ConsoleProgress::note, message), so that they do not
// break into its line. Returns the summary (O(samples)); an empty one for
// Nothing, which skips it.
ValueSummary report_loaded_volume(const std::string& command, const std::string& input, const Volume& volume,
                                  LoadReport report, ConsoleProgress* progress = nullptr);

// True for generated inputs (builtin:NAME[:N]), whose surface is at 0.
bool is_builtin_volume(const std::string& input);

}  // namespace isowave::cli

#pragma once
// Volume reader options shared by the subcommands that read volumes (extract,
// and fit and convert later): --dims, --type, --endian, --spacing, --origin,
// --field and --grid, turned into isowave::VolumeReadOptions.
#include <string>
#include <vector>

#include "cli.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"

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

// True for generated inputs (builtin:NAME[:N]), whose surface is at 0.
bool is_builtin_volume(const std::string& input);

}  // namespace isowave::cli

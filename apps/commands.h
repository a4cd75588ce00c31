#pragma once
// One function per subcommand; each returns the process exit code and may
// throw isowave::Error, which main() reports on one line.
#include <string>
#include <vector>

namespace isowave::commands {

using Args = std::vector<std::string>;

int subdivide(const Args& args);
int extract(const Args& args);
int convert(const Args& args);
int decode(const Args& args);
int stats(const Args& args);
int info(const Args& args);
int fit(const Args& args);
int simplify(const Args& args);

}  // namespace isowave::commands

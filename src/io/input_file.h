// Reading scene input files (the scene itself, Include/Import, PLY, spectra, glTF buffers).
#pragma once

#include <string>

namespace caustica {

// The whole file at `path`. Throws std::runtime_error saying why it cannot be read, without
// the path (callers write "cannot read \"<path>\": " + what()): "is a directory", "is not a
// regular file", or the system's reason ("No such file or directory"). The checks are explicit
// because on Linux a directory opens as a stream and reads as empty, and a FIFO or a device would
// block or never end.
std::string read_input_file(const std::string& path);

}  // namespace caustica

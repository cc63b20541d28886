// Reading the files irslam is given (config, saved map, world) without trusting
// them: only a regular file (a FIFO, a device or a directory is refused before it
// can hang or exhaust anything), at most max_bytes, one-line errors.
#ifndef IRSLAM_IO_FILE_IO_H_
#define IRSLAM_IO_FILE_IO_H_

#include <cstddef>
#include <string>

namespace irslam {

// Reads the whole file at path into *text. False with "cannot read PATH: why" in
// *error when it cannot be opened, is not a regular file, or is larger than
// max_bytes.
bool ReadRegularFile(const std::string& path, size_t max_bytes, std::string* text,
                     std::string* error);

}  // namespace irslam

#endif  // IRSLAM_IO_FILE_IO_H_

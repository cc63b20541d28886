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

// Writes text to PATH.tmp, then renames it over path, so a reader never sees a
// half-written file (the tools' outputs: maps, SVG, PGM; not the daemon's saved
// map, which daemon/map_store writes with O_EXCL|O_NOFOLLOW and fsync). False when
// it cannot be written.
bool WriteFileReplacing(const std::string& path, const std::string& text);

}  // namespace irslam

#endif  // IRSLAM_IO_FILE_IO_H_

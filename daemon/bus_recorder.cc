#include "daemon/bus_recorder.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace irslam {

BusRecorder::BusRecorder(std::string state_dir, RecordSettings settings, RecordHeader header,
                         std::string iface)
    : dir_(std::move(state_dir)),
      path_(dir_ + "/bus.log"),
      settings_(settings),
      header_(header),
      iface_(std::move(iface)) {
  stats_.path = path_;
}

BusRecorder::~BusRecorder() { Close(); }

void BusRecorder::Close() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (writer_.joinable()) writer_.join();
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool BusRecorder::Open(std::string* error) {
  ::mkdir(dir_.c_str(), 0750);  // usually there already (systemd StateDirectory=)
  struct stat st{};
  if (::stat(path_.c_str(), &st) == 0 && st.st_size > 0 && !Rotate(error)) return false;
  if (!OpenFile(error)) return false;
  writer_ = std::thread([this] { WriterLoop(); });
  return true;
}

bool BusRecorder::OpenFile(std::string* error) {
  fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd_ < 0) {
    *error = "cannot open " + path_ + ": " + std::strerror(errno);
    return false;
  }
  file_has_lines_ = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    stats_.bytes = 0;
  }
  return WriteAll(FormatRecordHeader(header_) + "\n", error);
}

// bus.log -> bus.log.1 -> ... -> bus.log.(files-1); the oldest is overwritten.
bool BusRecorder::Rotate(std::string* error) {
  if (fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  const auto name = [this](int i) { return i == 0 ? path_ : path_ + "." + std::to_string(i); };
  if (settings_.files <= 1) {
    ::unlink(path_.c_str());
  } else {
    for (int i = settings_.files - 2; i >= 0; --i) {
      if (std::rename(name(i).c_str(), name(i + 1).c_str()) != 0 && errno != ENOENT) {
        *error = "cannot rotate " + name(i) + ": " + std::strerror(errno);
        return false;
      }
    }
  }
  std::lock_guard<std::mutex> lock(mu_);
  ++stats_.rotations;
  return true;
}

bool BusRecorder::WriteAll(const std::string& text, std::string* error) {
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd_, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      *error = "cannot write " + path_ + ": " + std::strerror(errno);
      return false;
    }
    done += static_cast<size_t>(n);
  }
  std::lock_guard<std::mutex> lock(mu_);
  stats_.bytes += text.size();
  return true;
}

int64_t BusRecorder::StampNs(double t_s) const {
  // irslamd's robot time is whole microseconds of wall time (Daemon::RobotNow).
  return header_.origin_ns + std::llround(t_s / header_.time_scale * 1e6) * 1000;
}

void BusRecorder::Record(const can_frame& frame, double t_s) { Append(FormatLogLine(StampNs(t_s), iface_, frame)); }

void BusRecorder::Note(std::string_view event, double t_s) { Append(FormatEventComment(StampNs(t_s), event)); }

void BusRecorder::Append(std::string line) {
  line += '\n';
  bool wake = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (failed_ || pending_.size() + line.size() > static_cast<size_t>(settings_.buffer_bytes)) {
      ++stats_.dropped;
      return;
    }
    pending_ += line;
    wake = pending_.size() >= static_cast<size_t>(settings_.buffer_bytes) / 4;
  }
  if (wake) wake_.notify_one();
}

void BusRecorder::WriterLoop() {
  std::string chunk;
  for (;;) {
    bool stop = false;
    uint64_t lines = 0;
    {
      std::unique_lock<std::mutex> lock(mu_);
      // Woken when a quarter of the buffer is used, else every 200 ms (wall time).
      wake_.wait_for(lock, std::chrono::milliseconds(200), [this] {
        return stopping_ || pending_.size() >= static_cast<size_t>(settings_.buffer_bytes) / 4;
      });
      chunk.swap(pending_);
      pending_.clear();
      stop = stopping_;
      if (failed_) chunk.clear();
    }
    for (char c : chunk) lines += c == '\n';
    std::string error;
    bool ok = true;
    // Whole lines into each file; a new file when the next line would pass max_bytes.
    size_t from = 0;
    while (ok && from < chunk.size()) {
      uint64_t bytes = 0;
      {
        std::lock_guard<std::mutex> lock(mu_);
        bytes = stats_.bytes;
      }
      const uint64_t room = static_cast<uint64_t>(settings_.max_bytes) - std::min<uint64_t>(bytes, settings_.max_bytes);
      size_t to = from;
      while (to < chunk.size()) {
        const size_t end = chunk.find('\n', to) + 1;  // every line ends with '\n'
        if (end - from > room) break;
        to = end;
      }
      if (to == from) {
        if (file_has_lines_) {
          ok = Rotate(&error) && OpenFile(&error);
          continue;
        }
        to = chunk.find('\n', from) + 1;  // a file holds at least one line, whatever max_bytes
      }
      ok = ok && WriteAll(chunk.substr(from, to - from), &error);
      file_has_lines_ = true;
      from = to;
    }
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (ok) {
        stats_.lines += lines;
      } else {
        stats_.dropped += lines;
        stats_.error = error;
        failed_ = true;
        std::fprintf(stderr, "<3>irslamd: record: %s: recording stopped\n", error.c_str());
      }
    }
    chunk.clear();
    if (stop) return;
  }
}

RecorderStats BusRecorder::stats() const {
  std::lock_guard<std::mutex> lock(mu_);
  return stats_;
}

}  // namespace irslam

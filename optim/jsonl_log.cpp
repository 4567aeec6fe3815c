#include "optim/jsonl_log.h"

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::optim {

namespace fs = std::filesystem;

JsonlLog::JsonlLog(const std::string& path, long long keep_bytes) : path_(path) {
  if (keep_bytes < 0) {
    WriteFileAtomically(path_, "");
  } else if (fs::exists(path_) && std::int64_t(fs::file_size(path_)) > keep_bytes) {
    fs::resize_file(path_, std::uintmax_t(keep_bytes));
  }
  out_.open(path_, std::ios::app);
  if (!out_) throw Error(path_ + ": cannot write");
}

CallbackReturnType JsonlLog::operator()(const IterationSummary& s) {
  errno = 0;
  out_ << s.ToJson().dump() << "\n";
  out_.flush();
  if (!out_) throw Error(path_ + ": cannot write: " + (errno ? std::strerror(errno) : "disk full?"));
  return CallbackReturnType::kContinue;
}

long long JsonlLog::bytes() {
  out_.flush();
  return (long long)fs::file_size(path_);
}

}  // namespace quijibo::optim

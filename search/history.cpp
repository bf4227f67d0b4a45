#include "search/history.h"

#include <fcntl.h>
#include <unistd.h>

#include <fstream>
#include <spdlog/spdlog.h>

#include "core/atomic_file.h"
#include "core/error.h"

namespace cgsr {

SearchHistory::SearchHistory(std::filesystem::path path, bool resume) : path_(std::move(path)) {
  if (!std::filesystem::exists(path_)) return;
  if (!resume)
    throw Error(path_.string(), "a search history exists already: pass --resume to continue it, or use a new --out");
  const std::string text = read_file(path_);
  size_t start = 0, valid_end = 0;
  int line_number = 0;
  while (start < text.size()) {
    const size_t end = text.find('\n', start);
    ++line_number;
    if (end == std::string::npos) {  // no newline: the write of this line was cut short
      ++dropped_;
      break;
    }
    try {
      const auto j = nlohmann::json::parse(text.substr(start, end - start));
      HistoryEntry e;
      e.generation = j.at("generation");
      e.spec = spec_from_yaml(j.at("spec").get<std::string>(), path_.string() + ":" + std::to_string(line_number));
      e.key = j.at("key");
      e.score = j.at("score").get<CandidateScore>();
      index_[e.key] = entries_.size();
      entries_.push_back(std::move(e));
      valid_end = end + 1;
    } catch (const nlohmann::json::exception& ex) {
      throw Error(path_.string() + ":" + std::to_string(line_number), std::string("corrupt history line: ") + ex.what());
    }
    start = end + 1;
  }
  if (dropped_) {
    spdlog::warn("{}: dropped {} incomplete line(s) left by an interrupted run", path_.string(), dropped_);
    write_file_atomic(path_, text.substr(0, valid_end));
  }
}

const HistoryEntry* SearchHistory::find(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? nullptr : &entries_[it->second];
}

void SearchHistory::append(const HistoryEntry& entry) {
  nlohmann::ordered_json j;
  j["generation"] = entry.generation;
  j["key"] = entry.key;
  j["spec"] = spec_to_yaml(entry.spec);
  j["summary"] = spec_summary(entry.spec);
  j["score"] = entry.score;
  const std::string line = j.dump() + "\n";
  // One write of a whole line, then fsync: a kill leaves at most one partial last line.
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) throw Error(path_.string(), "cannot open the history for appending");
  const ssize_t written = ::write(fd, line.data(), line.size());
  ::fsync(fd);
  ::close(fd);
  if (written != static_cast<ssize_t>(line.size())) throw Error(path_.string(), "write failed (disk full?)");
  index_[entry.key] = entries_.size();
  entries_.push_back(entry);
}

}  // namespace cgsr

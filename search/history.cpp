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
      Candidate e;
      const std::string where = path_.string() + ":" + std::to_string(line_number);
      e.generation = j.at("generation");
      e.subnet = subnet_from_json(j.at("subnet"), where);
      e.key = j.at("key");
      e.failed = j.at("failed");
      if (!e.failed) e.score = j.at("score").get<SubnetScore>();
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

const Candidate* SearchHistory::find(const std::string& key) const {
  const auto it = index_.find(key);
  return it == index_.end() ? nullptr : &entries_[it->second];
}

void SearchHistory::append(const std::vector<Candidate>& candidates) {
  if (candidates.empty()) return;
  std::string text;
  for (const auto& c : candidates) {
    nlohmann::ordered_json j;
    j["generation"] = c.generation;
    j["key"] = c.key;
    j["subnet"] = to_json(c.subnet);
    j["failed"] = c.failed;
    if (!c.failed) j["score"] = c.score;
    text += j.dump() + "\n";
  }
  // One write, then fsync: a kill leaves at most one partial last line.
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) throw Error(path_.string(), "cannot open the history for appending");
  const ssize_t written = ::write(fd, text.data(), text.size());
  ::fsync(fd);
  ::close(fd);
  if (written != static_cast<ssize_t>(text.size())) throw Error(path_.string(), "write failed (disk full?)");
  for (const auto& c : candidates) {
    index_[c.key] = entries_.size();
    entries_.push_back(c);
  }
}

}  // namespace cgsr

#pragma once
// The search history: one JSON line per evaluated subnet, appended and flushed to disk after
// every generation. It is the search's checkpoint: a resumed search replays its generations and
// takes every score already in the history instead of evaluating again. A line cut short by a
// kill is dropped on reading.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "search/strategy.h"

namespace cgsr {

class SearchHistory {
 public:
  // Opens (and with `resume`, reads) the history file; without `resume` an existing file is an
  // error, so a finished search is never overwritten by accident.
  SearchHistory(std::filesystem::path path, bool resume);

  const Candidate* find(const std::string& key) const;
  // One write of all the lines, then fsync.
  void append(const std::vector<Candidate>& candidates);
  const std::vector<Candidate>& entries() const { return entries_; }
  int dropped_lines() const { return dropped_; }

 private:
  std::filesystem::path path_;
  std::vector<Candidate> entries_;
  std::map<std::string, size_t> index_;
  int dropped_ = 0;
};

}  // namespace cgsr

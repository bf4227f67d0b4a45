#pragma once
// The search history: one JSON line per evaluated candidate (and one for the parent), appended
// and flushed to disk after every evaluation. It is the search's checkpoint: a resumed search
// replays its generations and takes every score already in the history instead of training
// again. A line cut short by a kill is dropped on reading.

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "models/arch_spec.h"
#include "search/evaluator.h"

namespace cgsr {

struct HistoryEntry {
  int generation = 0;  // -1 for the parent
  ArchSpec spec;
  std::string key;
  CandidateScore score;
};

class SearchHistory {
 public:
  // Opens (and with `resume`, reads) the history file; without `resume` an existing file is an
  // error, so a finished search is never overwritten by accident.
  SearchHistory(std::filesystem::path path, bool resume);

  const HistoryEntry* find(const std::string& key) const;
  void append(const HistoryEntry& entry);
  const std::vector<HistoryEntry>& entries() const { return entries_; }
  int dropped_lines() const { return dropped_; }

 private:
  std::filesystem::path path_;
  std::vector<HistoryEntry> entries_;
  std::map<std::string, size_t> index_;
  int dropped_ = 0;
};

}  // namespace cgsr

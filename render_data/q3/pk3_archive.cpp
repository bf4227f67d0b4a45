#include "render_data/q3/pk3_archive.h"

#include <zip.h>

#include <algorithm>

#include "core/error.h"
#include "render_data/q3/script_tokens.h"

namespace cgsr::q3 {
namespace {

constexpr uint64_t kMaxEntryBytes = 512ull << 20;

std::string zip_error_text(int code) {
  zip_error_t error;
  zip_error_init_with_code(&error, code);
  std::string text = zip_error_strerror(&error);
  zip_error_fini(&error);
  return text;
}

}  // namespace

std::string normalize_game_path(const std::string& name) {
  std::string out = ascii_lower(name);
  std::replace(out.begin(), out.end(), '\\', '/');
  return out;
}

struct Pk3Archive::Handle {
  zip_t* zip = nullptr;
  ~Handle() {
    if (zip) zip_discard(zip);  // read-only: nothing to write back
  }
};

Pk3Archive::Pk3Archive(const std::filesystem::path& path) : path_(path), handle_(std::make_unique<Handle>()) {
  int code = 0;
  handle_->zip = zip_open(path.c_str(), ZIP_RDONLY, &code);
  if (!handle_->zip) throw Error(path.string(), "cannot open as a pk3 (zip) archive: " + zip_error_text(code));
  const zip_int64_t count = zip_get_num_entries(handle_->zip, 0);
  if (count < 0) throw Error(path.string(), "cannot list the archive's entries");
  for (zip_int64_t i = 0; i < count; ++i) {
    const char* name = zip_get_name(handle_->zip, static_cast<zip_uint64_t>(i), 0);
    if (!name) throw Error(path.string(), "entry " + std::to_string(i) + " has no readable name");
    std::string entry(name);
    if (entry.empty() || entry.back() == '/') continue;  // a directory
    names_.push_back(std::move(entry));
    zip_indices_.push_back(static_cast<uint64_t>(i));
  }
}

Pk3Archive::~Pk3Archive() = default;

std::vector<uint8_t> Pk3Archive::read(size_t index) const {
  if (index >= names_.size()) throw Error(path_.string(), "entry index out of range", ErrorKind::Internal);
  const std::string context = path_.string() + ":" + names_[index];
  zip_stat_t stat;
  zip_stat_init(&stat);
  if (zip_stat_index(handle_->zip, zip_indices_[index], 0, &stat) != 0 || !(stat.valid & ZIP_STAT_SIZE))
    throw Error(context, "cannot read the entry's size");
  if (stat.size > kMaxEntryBytes) throw Error(context, "entry of " + std::to_string(stat.size) + " bytes is too large");
  zip_file_t* file = zip_fopen_index(handle_->zip, zip_indices_[index], 0);
  if (!file) throw Error(context, std::string("cannot open the entry: ") + zip_strerror(handle_->zip));
  std::vector<uint8_t> bytes(static_cast<size_t>(stat.size));
  zip_uint64_t done = 0;
  while (done < stat.size) {
    const zip_int64_t got = zip_fread(file, bytes.data() + done, stat.size - done);
    if (got <= 0) {
      const std::string why = got < 0 ? zip_file_strerror(file) : "unexpected end of data";
      zip_fclose(file);
      throw Error(context, "cannot decompress the entry: " + why);
    }
    done += static_cast<zip_uint64_t>(got);
  }
  // A checksum mismatch is reported at close.
  const int closed = zip_fclose(file);
  if (closed != 0) throw Error(context, "corrupt entry: " + zip_error_text(closed));
  return bytes;
}

void Pk3FileSystem::add_archive(const std::filesystem::path& path) {
  auto archive = std::make_unique<Pk3Archive>(path);
  std::lock_guard<std::mutex> lock(mutex_);
  const size_t slot = archives_.size();
  for (size_t i = 0; i < archive->entries().size(); ++i)
    files_[normalize_game_path(archive->entries()[i])] = Location{slot, i};
  archives_.push_back(std::move(archive));
}

int Pk3FileSystem::add_directory(const std::filesystem::path& directory) {
  std::error_code ec;
  if (!std::filesystem::is_directory(directory, ec)) throw Error(directory.string(), "not a directory");
  std::vector<std::filesystem::path> pk3s;
  for (const auto& item : std::filesystem::directory_iterator(directory, ec)) {
    const std::string extension = normalize_game_path(item.path().extension().string());
    if (item.is_regular_file() && extension == ".pk3") pk3s.push_back(item.path());
  }
  if (ec) throw Error(directory.string(), "cannot list the directory: " + ec.message());
  std::sort(pk3s.begin(), pk3s.end());
  for (const auto& pk3 : pk3s) add_archive(pk3);
  return static_cast<int>(pk3s.size());
}

const Pk3FileSystem::Location* Pk3FileSystem::find(const std::string& name) const {
  const auto it = files_.find(normalize_game_path(name));
  return it == files_.end() ? nullptr : &it->second;
}

bool Pk3FileSystem::contains(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return find(name) != nullptr;
}

std::optional<std::vector<uint8_t>> Pk3FileSystem::try_read(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Location* at = find(name);
  if (!at) return std::nullopt;
  return archives_[at->archive]->read(at->entry);
}

std::vector<uint8_t> Pk3FileSystem::read(const std::string& name) const {
  auto bytes = try_read(name);
  if (!bytes)
    throw Error(name, "not found in any of the " + std::to_string(archives_.size()) + " pk3 archives");
  return std::move(*bytes);
}

std::string Pk3FileSystem::describe(const std::string& name) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const Location* at = find(name);
  if (!at) return "";
  const Pk3Archive& archive = *archives_[at->archive];
  return archive.path().filename().string() + ":" + archive.entries()[at->entry];
}

std::vector<std::string> Pk3FileSystem::list(const std::string& prefix, const std::string& suffix) const {
  const std::string p = normalize_game_path(prefix), s = normalize_game_path(suffix);
  std::vector<std::string> out;
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& [name, location] : files_)
    if (name.size() >= p.size() + s.size() && name.compare(0, p.size(), p) == 0 &&
        name.compare(name.size() - s.size(), s.size(), s) == 0)
      out.push_back(name);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace cgsr::q3

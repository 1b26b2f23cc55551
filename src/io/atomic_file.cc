#include "lmcal/io/atomic_file.hpp"

#include <fstream>

#include "lmcal/error.hpp"

namespace lmcal {

namespace fs = std::filesystem;

void OutputSet::add(fs::path path, std::string contents) {
  files_.emplace_back(std::move(path), std::move(contents));
}

void OutputSet::commit() {
  std::vector<fs::path> temporaries;
  auto discard = [&] {
    std::error_code ignored;
    for (const auto& t : temporaries) fs::remove(t, ignored);
  };
  try {
    for (const auto& [path, contents] : files_) {
      if (path.has_parent_path()) {
        std::error_code ec;
        fs::create_directories(path.parent_path(), ec);
        if (ec) throw InputError(path.parent_path().string(), 0, 0, "cannot create folder: " + ec.message());
      }
      fs::path temporary = path;
      temporary += ".tmp";
      temporaries.push_back(temporary);
      std::ofstream stream(temporary, std::ios::binary | std::ios::trunc);
      stream.write(contents.data(), static_cast<std::streamsize>(contents.size()));
      stream.close();
      if (!stream) throw InputError(path.string(), 0, 0, "cannot write output file");
    }
    for (std::size_t i = 0; i < files_.size(); ++i) {
      std::error_code ec;
      fs::rename(temporaries[i], files_[i].first, ec);
      if (ec) throw InputError(files_[i].first.string(), 0, 0, "cannot move output into place: " + ec.message());
    }
  } catch (...) {
    discard();
    throw;
  }
  files_.clear();
}

void write_file_atomically(const fs::path& path, const std::string& contents) {
  OutputSet set;
  set.add(path, contents);
  set.commit();
}

}  // namespace lmcal

// A large tidy friction-log file read in slices side by side, joined in file order as one
// reader would have read it (or SlicesDisagree, and the file is read line by line).
#include "friction_file_loader.hpp"

#include <algorithm>
#include <functional>
#include <tuple>
#include <cmath>
#include <memory>

#include "parallel_slices.hpp"
#include "lmcal/error.hpp"

namespace lmcal::detail::friction_reading {

void FileLoader::read_slices(int count) {
  std::optional<csv::Reader::Rest> rest = reader_.read_rest(count);
  if (!rest) {  // being written: line by line
    read_rows();
    report_.bytes = static_cast<double>(reader_.bytes());
    return;
  }
  if (!column(kRun)) file_run_name();  // its note once, in this file's report
  struct Part {
    FrictionLog log;
    NameIndex runs{log.run_names}, guides{log.guide_names};
    std::unique_ptr<FileLoader> loader;
  };
  std::vector<std::unique_ptr<Part>> parts;
  const double rows_per_byte = static_cast<double>(reader_.estimated_rows()) /
                               static_cast<double>(std::max<std::uintmax_t>(1, reader_.file_size()));
  for (std::size_t k = 0; k < rest->slices.size(); ++k) {
    auto& part = parts.emplace_back(std::make_unique<Part>());
    if (k == 0) {
      part->loader.reset(new FileLoader(*this, rest->slices[0], reader_.line(), log_, runs_, guides_));
      continue;
    }
    part->log.law = log_.law;
    part->loader.reset(new FileLoader(*this, rest->slices[k], 0, part->log, part->runs, part->guides));
  }
  detail::for_each_slice(parts.size(), static_cast<int>(parts.size()), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      // A slice's own log mapped by the thread that fills it.
      if (k != 0) reserve(parts[k]->log, static_cast<std::size_t>(rows_per_byte * static_cast<double>(rest->slices[k].size())) + 16);
      parts[k]->loader->read_rows();
    }
  });
  std::vector<LastSample> last = parts[0]->loader->last_;  // by the log's run index
  long lines_before = parts[0]->loader->reader_.line();
  std::vector<JoinedPart> joined;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    FileLoader& part = *parts[k]->loader;
    if (k != 0) {
      joined.push_back(join(part, lines_before, last));
      lines_before += part.reader_.line();
    }
    report_.rows_read += part.report_.rows_read;
    skipped_ += part.skipped_;
    backward_rows_ += part.backward_rows_;
    negative_backward_ += part.negative_backward_;
    negative_rows_ += part.negative_rows_;
  }
  if (report_.rows_read > io::kMaxRows) throw SlicesDisagree();
  append_parts(joined);
  report_.bytes = static_cast<double>(reader_.file_size());
}

FileLoader::JoinedPart FileLoader::join(const FileLoader& part, long lines_before, std::vector<LastSample>& last) {
  const FrictionLog& from = part.log_;
  const std::vector<std::uint32_t> run_map = map_names<SlicesDisagree>(runs_, from.run_names);
  const std::vector<std::uint32_t> guide_map = map_names<SlicesDisagree>(guides_, from.guide_names);
  join_law(from.law);
  if (last.size() < runs_.size()) last.resize(runs_.size());
  for (std::size_t r = 0; r < part.last_.size(); ++r) {
    const LastSample& sample = part.last_[r];
    if (sample.line == 0) continue;
    LastSample& before = last[run_map[r]];
    if (sample.first_s < before.time_s) throw SlicesDisagree();
    before = {sample.time_s, sample.line + lines_before, before.line == 0 ? sample.first_s : before.first_s};
  }
  return {&from, std::move(run_map), std::move(guide_map), lines_before};
}

void FileLoader::append_parts(const std::vector<JoinedPart>& parts) {
  // One task per column, each appending every part in order: the copies (and the first touch of
  // the log's reserved pages) side by side, the same rows as one part after another.
  std::vector<std::function<void()>> tasks;
  const auto copied = [&](auto FrictionLog::*column) {
    tasks.emplace_back([this, &parts, column] {
      auto& to = log_.*column;
      for (const JoinedPart& part : parts) to.insert(to.end(), (part.log->*column).begin(), (part.log->*column).end());
    });
  };
  const auto mapped = [&](std::vector<std::uint32_t> FrictionLog::*column, auto map) {
    tasks.emplace_back([this, &parts, column, map] {
      auto& to = log_.*column;
      for (const JoinedPart& part : parts)
        for (std::uint32_t value : part.log->*column) to.push_back(map(part, value));
    });
  };
  mapped(&FrictionLog::run, [](const JoinedPart& part, std::uint32_t r) { return part.run_map[r]; });
  mapped(&FrictionLog::guide, [](const JoinedPart& part, std::uint32_t g) { return part.guide_map[g]; });
  mapped(&FrictionLog::line, [](const JoinedPart& part, std::uint32_t l) { return l + static_cast<std::uint32_t>(part.lines_before); });
  std::apply([&](auto... member) { (copied(member), ...); }, kValueColumns);
  detail::for_each_index(tasks.size(), [&](std::size_t t) { tasks[t](); });
}

void FileLoader::join_law(const FrictionLawConditions& from) {
  FrictionLawConditions& law = log_.law;
  for (std::optional<double> FrictionLawConditions::*stated :
       {&FrictionLawConditions::load_N, &FrictionLawConditions::preload_um, &FrictionLawConditions::block_length_mm,
        &FrictionLawConditions::preload_N}) {
    if (!(from.*stated)) continue;
    if (!(law.*stated)) law.*stated = from.*stated;
    if (*(law.*stated) != *(from.*stated)) throw SlicesDisagree();
  }
  if (!law.preload_class) law.preload_class = from.preload_class;
}

}  // namespace lmcal::detail::friction_reading

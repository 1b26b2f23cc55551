// A large tidy friction-log file read in slices side by side, joined in file order as one
// reader would have read it (or SlicesDisagree, and the file is read line by line).
#include "friction_file_loader.hpp"

#include <algorithm>
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
    reserve(part->log, static_cast<std::size_t>(rows_per_byte * static_cast<double>(rest->slices[k].size())) + 16);
  }
  detail::for_each_slice(parts.size(), static_cast<int>(parts.size()), [&](int, std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) parts[k]->loader->read_rows();
  });
  std::vector<LastSample> last = parts[0]->loader->last_;  // by the log's run index
  long lines_before = parts[0]->loader->reader_.line();
  for (std::size_t k = 0; k < parts.size(); ++k) {
    FileLoader& part = *parts[k]->loader;
    if (k != 0) {
      join(part, lines_before, last);
      lines_before += part.reader_.line();
    }
    report_.rows_read += part.report_.rows_read;
    skipped_ += part.skipped_;
    backward_rows_ += part.backward_rows_;
    negative_backward_ += part.negative_backward_;
    negative_rows_ += part.negative_rows_;
  }
  if (report_.rows_read > io::kMaxRows) throw SlicesDisagree();
  report_.bytes = static_cast<double>(reader_.file_size());
}

void FileLoader::join(const FileLoader& part, long lines_before, std::vector<LastSample>& last) {
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
  const auto append = [](auto& to, const auto& more) { to.insert(to.end(), more.begin(), more.end()); };
  for (std::uint32_t r : from.run) log_.run.push_back(run_map[r]);
  for (std::uint32_t g : from.guide) log_.guide.push_back(guide_map[g]);
  for (std::uint32_t l : from.line) log_.line.push_back(l + static_cast<std::uint32_t>(lines_before));
  append(log_.time_s, from.time_s);
  append(log_.velocity_m_s, from.velocity_m_s);
  append(log_.load_N, from.load_N);
  append(log_.preload_um, from.preload_um);
  append(log_.block_length_mm, from.block_length_mm);
  append(log_.temperature_C, from.temperature_C);
  append(log_.friction_N, from.friction_N);
  append(log_.viscosity40_mm2_s, from.viscosity40_mm2_s);
  append(log_.direction, from.direction);
  append(log_.acceleration_m_s2, from.acceleration_m_s2);
  append(log_.position_m, from.position_m);
  append(log_.distance_since_reversal_m, from.distance_since_reversal_m);
  append(log_.time_since_reversal_s, from.time_since_reversal_s);
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

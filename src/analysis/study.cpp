// The parameter study of `compare`: a grid of job variants (every combination of the varied
// keys' values), each built from one parsed document and evaluated in parallel (analysis.hpp).
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "trochomill/analysis.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"

namespace trochomill {
namespace {

// "a, [1, 2], b" -> {"a", " [1, 2]", " b"}: commas inside brackets, braces and quotes kept.
std::vector<std::string> split_values(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  bool quoted = false;
  for (const char c : text) {
    if (c == '"') quoted = !quoted;
    if (!quoted && (c == '[' || c == '{')) ++depth;
    if (!quoted && (c == ']' || c == '}')) --depth;
    if (c == ',' && depth == 0 && !quoted) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

}  // namespace

Vary parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) {
    throw InputError(fmt::format("'{}': expected section.key=v1,v2,...", text));
  }
  Vary v;
  v.key = trim(text.substr(0, eq));
  const auto dot = v.key.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == v.key.size()) {
    throw InputError(
        fmt::format("'{}': the key must be section.key (e.g. path.aspect_ratio)", text));
  }
  for (auto& val : split_values(text.substr(eq + 1))) {
    val = trim(val);
    if (val.empty()) throw InputError(fmt::format("'{}': empty value in the list", text));
    v.values.push_back(val);
  }
  return v;
}

std::vector<StudyPoint> run_study(const JobDocument& doc, const std::vector<Override>& base,
                                  const std::vector<Vary>& varies, int threads,
                                  const std::function<ProcessMetrics(const Job&)>& evaluate,
                                  const RunHooks& hooks) {
  if (varies.empty())
    throw InputError("compare: give at least one key to vary (section.key and its values)");
  std::size_t total = 1;
  for (const auto& v : varies) total *= v.values.size();
  if (total > 100000) {
    throw InputError(fmt::format("compare: the grid has {} points (limit 100000)", total));
  }
  std::vector<StudyPoint> points(total);
  for (std::size_t p = 0; p < total; ++p) {
    std::size_t rest = p;
    std::vector<Override> ov = base;
    std::vector<std::size_t> idx(varies.size());
    for (std::size_t k = varies.size(); k-- > 0;) {  // the last vary changes fastest
      idx[k] = rest % varies[k].values.size();
      rest /= varies[k].values.size();
    }
    for (std::size_t k = 0; k < varies.size(); ++k) {
      // Named by its key in messages (the point's values are named with them).
      ov.push_back(Override{varies[k].key, varies[k].values[idx[k]], ""});
    }
    points[p].overrides = std::move(ov);
  }
  hooks.begin("grid");
  SharedProgress progress(hooks, total);
  auto run_one = [&](std::size_t p) {
    hooks.check();
    StudyPoint& sp = points[p];
    try {
      sp.metrics = evaluate(doc.build(sp.overrides));
      sp.metrics.series = EngagementSeries{};  // keep the study small
      sp.ok = true;
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      sp.error = e.what();
    }
    progress.add(1);
  };
  const int n_threads = threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(n_threads);
  arena.execute(
      [&] { tbb::parallel_for(std::size_t{0}, total, [&](std::size_t p) { run_one(p); }); });
  return points;
}

}  // namespace trochomill

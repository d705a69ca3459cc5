// `trochomill sweep`: a grid and/or a space-filling sample of job keys, each point evaluated
// with analyze, mechanism, forces (fast chips) or simulate, its metrics appended to a CSV in
// point order as points finish, resumable.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <boost/random/sobol.hpp>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "distributed.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/io.hpp"
#include "trochomill/mechanism.hpp"
#include "trochomill/pocket.hpp"
#include "trochomill/report.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/study.hpp"

namespace trochomill {
namespace {

using nlohmann::json;

constexpr std::size_t kMaxPoints = 1000000;
constexpr std::size_t kMaxComparePoints = 100000;

// What an interrupted sweep says.
const std::string& stopped_message() {
  static const std::string m =
      "interrupted: the rows written stay; " + option_name("resume") + " continues";
  return m;
}

// Measurements of the run itself differ from run to run: never metrics of a point.
bool measurement(const std::string& key) {
  // memory_mb (the boards' size) repeats from run to run, but is not a metric of the point.
  return is_run_measurement(key) || key == "memory_mb";
}

// The numeric leaves of a document (numbers, booleans as 0/1, nulls), nested keys joined by
// '.'; arrays and strings are not metrics.
void flatten(const json& j, const std::string& prefix,
             std::vector<std::pair<std::string, json>>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (measurement(it.key())) continue;
    if (it->is_object()) {
      flatten(*it, key, out);
    } else if (it->is_number() || it->is_boolean() || it->is_null()) {
      out.emplace_back(key, *it);
    }
  }
}

// analyze's evaluation of a point: the job's plan, its metrics with the predicted force (the
// parts asked for).
ProcessMetrics analyze_point(const Job& job, const RunHooks& hooks,
                             const AnalysisParts& parts = {}) {
  return analyze_with_forces(job, plan_job(job).path, hooks, parts);
}

// The overrides of point i: the base's, then the point's values (named by their keys).
std::vector<Override> point_overrides(const std::vector<Override>& base, const SweepPlan& plan,
                                      std::size_t i) {
  std::vector<Override> o = base;
  for (std::size_t k = 0; k < plan.keys.size(); ++k)
    o.push_back({plan.keys[k], plan.points[i][k], ""});
  return o;
}

// Runs run(k) for k in [0, count) on `threads` threads (0: all cores), a point per task, until
// the hooks cancel; a point stopped by Interrupted stops the rest. After the points that were
// running: Interrupted (`stopped`) when cancelled, else the point's own Interrupted.
template <class Run>
void for_each_point(std::size_t count, int threads, const RunHooks& hooks, const char* stopped,
                    const Run& run) {
  std::atomic<bool> stop{false};
  std::exception_ptr interrupted;
  std::mutex mu;
  tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
  arena.execute([&] {
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t k = r.begin(); k < r.end(); ++k) {
            if (stop || hooks.cancelled()) return;
            try {
              run(k);
            } catch (const Interrupted&) {
              const std::lock_guard<std::mutex> lock(mu);
              if (!interrupted) interrupted = std::current_exception();
              stop = true;
              return;
            }
          }
        },
        tbb::simple_partitioner());
  });
  hooks.check(stopped);
  if (interrupted) std::rethrow_exception(interrupted);
}

// The document of one evaluation.
json evaluate(const Job& job, SweepEval eval, const std::optional<std::pair<int, int>>& cycles,
              const RunHooks& hooks, double memory_limit_bytes, const AnalysisParts& parts = {}) {
  if (eval == SweepEval::mechanism) {
    const bool wear = job.tool.flank_wear_mm > 0;
    const MechanismCurve c = mechanism_curve(job, job.mechanism, wear);
    return json::parse(
        mechanism_json(job, job.mechanism, c, summarize_zones(c, job.mechanism, wear), wear));
  }
  if (eval == SweepEval::analyze) {
    return json::parse(metrics_json(job, analyze_point(job, hooks, parts)));
  }
  const ToolPath path = plan_job(job).path;
  std::pair<double, double> window;
  if (cycles) {
    window = cycle_window(path, cycles->first, cycles->second);
  } else {
    // The steady cycle is all the window needs (not the walls or the floor).
    const ProcessMetrics m = analyze_process(job, path, hooks, AnalysisParts::cycle_only());
    window = {m.cycle_start_s, m.cycle_start_s + m.cycle_time_s};
  }
  SimControl control;
  control.hooks = hooks;
  if (eval == SweepEval::forces) {
    if (!job.material.model) {
      throw InputError("no [material] force model (see `trochomill materials`)");
    }
    const JobForces f = job_forces(job, path, window.first, window.second, true, control);
    return json::parse(force_summary_json(job, f, window.first, window.second));
  }
  control.keep_records = false;  // only the summary is read
  if (memory_limit_bytes > 0) {
    const double need =
        estimate_simulation_memory(job, path, window.first, window.second).total(false);
    if (!(need <= memory_limit_bytes)) {
      throw InputError(fmt::format(
          "simulate: the estimated memory {} exceeds this point's share of the memory "
          "limit, {}: coarsen [simulation] resolution (now {} mm), shorten the window, "
          "or run fewer points at once",
          memory_text(need), memory_text(memory_limit_bytes), job.simulation.resolution_mm));
    }
  }
  const JobSimulation js = simulate_job(job, path, window.first, window.second, control);
  if (!js.result.complete) throw Interrupted("interrupted");
  return json::parse(simulation_json(job, js, window.first, window.second, 0, 0));
}

// CSV: a cell quoted when it holds a comma, a quote or a line break (those become spaces: a
// row is one line).
std::string cell(std::string text) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}
std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

std::string number_cell(const json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  const double d = v.get<double>();
  return std::isfinite(d) ? fmt::format("{}", d) : std::string();
}

void write_all(int fd, const std::string& text, const std::filesystem::path& file) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw IoError(fmt::format("{}: write failed: {}", file.string(), std::strerror(errno)));
    }
    done += static_cast<std::size_t>(n);
  }
}

// A deterministic uniform double in [0, 1) and integer in [0, n) from a 64-bit engine (the
// standard distributions differ between libraries).
double unit(std::mt19937_64& g) { return static_cast<double>(g() >> 11) * 0x1.0p-53; }
std::size_t below(std::mt19937_64& g, std::size_t n) {
  return static_cast<std::size_t>(g() % n);  // bias below n / 2^64: none that matters
}

// One point's CSV row (index, values, ok, error, metrics), its evaluation failing into the
// error cell; cancelling throws Interrupted.
std::string sweep_row(const JobDocument& doc, const std::vector<Override>& base,
                      const SweepPlan& plan, const SweepOptions& options,
                      const std::vector<std::string>& columns, std::size_t i,
                      const RunHooks& inner) {
  const std::vector<Override> o = point_overrides(base, plan, i);
  std::string error;
  std::map<std::string, json> values;
  try {
    Job job = doc.build(o);
    attach_rest_stock(job);  // [pocket] rest_of: the earlier program's stock
    std::vector<std::pair<std::string, json>> leaves;
    // The points in flight share the limit.
    const int in_flight =
        options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    flatten(evaluate(job, options.eval, options.cycles, inner,
                     options.memory_limit_bytes / std::max(1, in_flight)),
            "", leaves);
    for (auto& [k, v] : leaves) values.emplace(k, std::move(v));
  } catch (const Interrupted&) {
    throw;
  } catch (const std::exception& e) {
    error = e.what();
  }
  std::string line = fmt::format("{}", i);
  for (std::size_t k = 0; k < plan.keys.size(); ++k) {
    line += ',';
    line += cell(plan.points[i][k]);
  }
  line += error.empty() ? ",1," : ",0,";
  line += cell(error);
  for (std::size_t c = 3 + plan.keys.size(); c < columns.size(); ++c) {
    const auto it = values.find(columns[c]);
    line += ",";
    if (error.empty() && it != values.end()) line += number_cell(it->second);
  }
  return line + "\n";
}

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

std::map<std::string, double> point_metrics(const Job& job, SweepEval eval,
                                            const std::optional<std::pair<int, int>>& cycles,
                                            const RunHooks& hooks, double memory_limit_bytes,
                                            const AnalysisParts& parts) {
  std::vector<std::pair<std::string, json>> leaves;
  flatten(evaluate(job, eval, cycles, hooks, memory_limit_bytes, parts), "", leaves);
  std::map<std::string, double> out;
  for (const auto& [k, v] : leaves) {
    if (v.is_boolean()) {
      out.emplace(k, v.get<bool>() ? 1.0 : 0.0);
    } else if (v.is_number()) {
      const double d = v.get<double>();
      if (std::isfinite(d)) out.emplace(k, d);
    }
  }
  return out;
}

std::vector<std::string> metric_names(const Job& base, SweepEval eval) {
  const std::vector<std::string> cols = sweep_columns(SweepPlan{}, base, eval);
  return {cols.begin() + 3, cols.end()};  // after index, ok, error
}

SweepRange parse_range(const std::string& text, std::string_view option) {
  const std::string what = option.empty() ? option_name("ranges") : std::string(option);
  const auto eq = text.find('=');
  const auto colon = text.find(':', eq == std::string::npos ? 0 : eq);
  SweepRange r;
  if (eq == std::string::npos || colon == std::string::npos) {
    throw InputError(fmt::format("{} '{}': expected section.key=lo:hi", what, text));
  }
  r.key = trim(text.substr(0, eq));
  const std::string a = trim(text.substr(eq + 1, colon - eq - 1)), b = trim(text.substr(colon + 1));
  char* e1 = nullptr;
  char* e2 = nullptr;
  r.lo = std::strtod(a.c_str(), &e1);
  r.hi = std::strtod(b.c_str(), &e2);
  if (a.empty() || b.empty() || *e1 != '\0' || *e2 != '\0' || !std::isfinite(r.lo) ||
      !std::isfinite(r.hi) || !(r.lo < r.hi)) {
    throw InputError(
        fmt::format("{} '{}': expected section.key=lo:hi with finite numbers lo < hi", what, text));
  }
  return r;
}

Sampler parse_sampler(const std::string& name) {
  if (name == "sobol") return Sampler::sobol;
  if (name == "lhs") return Sampler::lhs;
  throw InputError(fmt::format("{} '{}': sobol or lhs", option_name("sampler"), name));
}

SweepEval parse_sweep_eval(const std::string& name) {
  for (const SweepEval e :
       {SweepEval::analyze, SweepEval::mechanism, SweepEval::forces, SweepEval::simulate}) {
    if (to_string(e) == name) return e;
  }
  throw InputError(
      fmt::format("{} '{}': analyze, mechanism, forces or simulate", option_name("eval"), name));
}

std::string_view to_string(SweepEval e) noexcept {
  switch (e) {
    case SweepEval::analyze:
      return "analyze";
    case SweepEval::mechanism:
      return "mechanism";
    case SweepEval::forces:
      return "forces";
    case SweepEval::simulate:
      return "simulate";
  }
  return "?";
}

std::vector<std::vector<double>> unit_samples(std::size_t samples, std::size_t dimensions,
                                              Sampler sampler, std::uint64_t seed) {
  std::vector<std::vector<double>> out(samples, std::vector<double>(dimensions));
  if (dimensions == 0) return out;
  if (sampler == Sampler::sobol) {
    if (dimensions > 3667)
      throw InputError(option_name("ranges") + ": Sobol's sequence has at most 3667 dimensions");
    boost::random::sobol gen(static_cast<unsigned>(dimensions));
    const double scale = static_cast<double>(gen.max()) + 1.0;
    for (auto& p : out) {
      for (double& x : p) x = static_cast<double>(gen()) / scale;
    }
    return out;
  }
  std::mt19937_64 g(seed);
  for (std::size_t d = 0; d < dimensions; ++d) {
    std::vector<std::size_t> perm(samples);
    for (std::size_t i = 0; i < samples; ++i) perm[i] = i;
    for (std::size_t i = samples; i > 1; --i) std::swap(perm[i - 1], perm[below(g, i)]);
    for (std::size_t i = 0; i < samples; ++i) {
      out[i][d] = (static_cast<double>(perm[i]) + unit(g)) / static_cast<double>(samples);
    }
  }
  return out;
}

SweepPlan plan_sweep(const std::vector<Vary>& grid, const std::vector<SweepRange>& ranges,
                     std::size_t samples, Sampler sampler, std::uint64_t seed) {
  SweepPlan plan;
  std::set<std::string> seen;
  const auto add_key = [&](const std::string& key, const std::string& option) {
    if (!find_job_key(key)) {
      throw InputError(fmt::format("{} {}: no such job key (see `trochomill keys`)", option, key));
    }
    if (!seen.insert(key).second) {
      throw InputError(fmt::format("{}: the key is given twice", key));
    }
    plan.keys.push_back(key);
  };
  for (const Vary& v : grid) {
    add_key(v.key, option_name("vary"));
    if (v.values.empty())
      throw InputError(fmt::format("{} {}: no values to take", option_name("vary"), v.key));
  }
  std::vector<bool> integer;
  for (const SweepRange& r : ranges) {
    add_key(r.key, option_name("ranges"));
    const JobKey* k = find_job_key(r.key);
    if (k->type != "number" && k->type != "integer") {
      throw InputError(fmt::format("{} {}: the key is {}, not a number (give its values with {})",
                                   option_name("ranges"), r.key, k->type, option_name("vary")));
    }
    integer.push_back(k->type == "integer");
  }
  if (ranges.empty() != (samples == 0)) {
    throw InputError(
        ranges.empty() ? option_name("samples") + " needs at least one " + option_name("ranges")
                       : option_name("ranges") + " needs " + option_name("samples") + " N (N > 0)");
  }
  if (grid.empty() && ranges.empty())
    throw InputError("sweep: give " + option_name("vary") + " or " + option_name("ranges"));
  double count = static_cast<double>(std::max<std::size_t>(samples, 1));
  for (const Vary& v : grid) count *= static_cast<double>(v.values.size());
  if (count > static_cast<double>(kMaxPoints)) {
    throw InputError(fmt::format("sweep: {:.0f} points, more than {}: fewer values or samples",
                                 count, kMaxPoints));
  }
  // The sample's values, once.
  std::vector<std::vector<std::string>> sampled;
  for (const auto& u : unit_samples(samples, ranges.size(), sampler, seed)) {
    std::vector<std::string> values;
    for (std::size_t d = 0; d < ranges.size(); ++d) {
      const double x = ranges[d].lo + u[d] * (ranges[d].hi - ranges[d].lo);
      values.push_back(integer[d] ? fmt::format("{}", std::llround(x)) : fmt::format("{:.12g}", x));
    }
    sampled.push_back(std::move(values));
  }
  if (sampled.empty()) sampled.emplace_back();
  // Grid (first key slowest) x sample.
  std::vector<std::size_t> idx(grid.size(), 0);
  for (;;) {
    for (const auto& s : sampled) {
      std::vector<std::string> values;
      for (std::size_t k = 0; k < grid.size(); ++k) values.push_back(grid[k].values[idx[k]]);
      values.insert(values.end(), s.begin(), s.end());
      plan.points.push_back(std::move(values));
    }
    std::size_t k = grid.size();
    while (k > 0) {
      if (++idx[k - 1] < grid[k - 1].values.size()) break;
      idx[k - 1] = 0;
      --k;
    }
    if (k == 0) break;
  }
  return plan;
}

std::vector<std::string> sweep_columns(const SweepPlan& plan, const Job& base, SweepEval eval) {
  json templ;
  switch (eval) {
    case SweepEval::analyze: {
      ProcessMetrics m;
      m.periodic = true;  // every optional figure present
      templ = json::parse(metrics_json(base, m));
      break;
    }
    case SweepEval::mechanism:
      templ =
          json::parse(mechanism_json(base, base.mechanism, MechanismCurve{}, ZoneSummary{}, false));
      break;
    case SweepEval::forces: {
      Job j = base;
      if (!j.material.model) j.material.model = ForceModel::linear;
      templ = json::parse(force_summary_json(j, JobForces{}, 0, 0));
      break;
    }
    case SweepEval::simulate:
      templ = json::parse(simulation_json(base, JobSimulation{}, 0, 0, 0, 0));
      break;
  }
  std::vector<std::string> cols = {"index"};
  cols.insert(cols.end(), plan.keys.begin(), plan.keys.end());
  cols.emplace_back("ok");
  cols.emplace_back("error");
  std::vector<std::pair<std::string, json>> leaves;
  flatten(templ, "", leaves);
  for (const auto& [k, v] : leaves) cols.push_back(k);
  return cols;
}

// A sweep's CSV text (read_sweep_csv); `csv` names it in messages.
static SweepTable parse_sweep_csv(const std::string& text, const std::filesystem::path& csv) {
  SweepTable t;
  std::size_t pos = 0;
  bool first = true;
  while (pos < text.size()) {
    const auto nl = text.find('\n', pos);
    if (nl == std::string::npos) break;  // a torn last line
    const std::string line = text.substr(pos, nl - pos);
    pos = nl + 1;
    if (first) {
      t.columns = split_csv_line(line);
      first = false;
      if (t.columns.empty() || t.columns[0] != "index") {
        throw InputError(fmt::format("{}: not a sweep's results (no index column)", csv.string()));
      }
      continue;
    }
    auto row = split_csv_line(line);
    if (row.size() != t.columns.size()) {
      throw InputError(fmt::format("{}:{}: {} cells, the header has {}", csv.string(),
                                   t.rows.size() + 2, row.size(), t.columns.size()));
    }
    t.rows.push_back(std::move(row));
  }
  if (first) throw InputError(fmt::format("{}: empty, not a sweep's results", csv.string()));
  return t;
}

SweepTable read_sweep_csv(const std::filesystem::path& csv) {
  return parse_sweep_csv(read_text_file(csv), csv);
}

std::string sweep_json(const SweepTable& t) {
  json points = json::array();
  for (const auto& row : t.rows) {
    json p = json::object();
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      const std::string& v = row[c];
      char* end = nullptr;
      const double d = std::strtod(v.c_str(), &end);
      if (t.columns[c] == "error") {
        p[t.columns[c]] = v;
      } else if (v.empty()) {
        p[t.columns[c]] = nullptr;
      } else if (*end == '\0' && std::isfinite(d)) {
        p[t.columns[c]] = d;
      } else {
        p[t.columns[c]] = v;
      }
    }
    points.push_back(std::move(p));
  }
  return json{{"columns", t.columns}, {"points", points}}.dump(2) + "\n";
}

// The sweep on this process: the file, and the points on local threads or, with a world of
// several ranks, handed out over MPI (this is rank 0). `told`: set once the other ranks were
// told to go.
static std::size_t run_sweep_here(const JobDocument& doc, const std::vector<Override>& base,
                                  const SweepPlan& plan, const SweepOptions& options,
                                  const std::filesystem::path& csv, bool resume,
                                  const RunHooks& hooks, const Distributed* world, bool& told) {
  const Job base_job = doc.build(base);
  const std::vector<std::string> columns = sweep_columns(plan, base_job, options.eval);
  std::string header;
  for (std::size_t c = 0; c < columns.size(); ++c) {
    if (c > 0) header += ',';
    header += cell(columns[c]);
  }
  header += '\n';

  // What is done already.
  std::vector<bool> done(plan.points.size(), false);
  const bool exists = std::filesystem::exists(csv);
  if (exists && !resume) {
    throw InputError(
        fmt::format("{} exists: {} continues that sweep, or remove the file to start again",
                    csv.string(), option_name("resume")));
  }
  // The output is locked while this sweep writes it: a second sweep of the same file (a
  // --resume started twice) refuses to start instead of writing the same rows again.
  const int fd = ::open(csv.c_str(), O_WRONLY | O_APPEND | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    throw IoError(
        fmt::format("{}: cannot open for writing: {}", csv.string(), std::strerror(errno)));
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EWOULDBLOCK) {
      throw InputError(fmt::format(
          "{}: another sweep is writing it (it holds the file's lock); wait for it to end, or "
          "give another output",
          csv.string()));
    }
    throw IoError(fmt::format("{}: cannot lock: {}", csv.string(), std::strerror(errno)));
  }
  if (exists) {
    // Drop a torn last line (a run killed while writing it).
    const std::string text = read_text_file(csv);
    const auto last = text.rfind('\n');
    const std::size_t keep = last == std::string::npos ? 0 : last + 1;
    if (keep < text.size()) std::filesystem::resize_file(csv, keep);
    if (keep > 0) {
      const SweepTable t = parse_sweep_csv(text.substr(0, keep), csv);  // read once
      if (t.columns != columns) {
        throw InputError(fmt::format(
            "{}: its columns are another sweep's (other keys or {}); give another output",
            csv.string(), option_name("eval")));
      }
      for (const auto& row : t.rows) {
        char* end = nullptr;
        const unsigned long long i = std::strtoull(row[0].c_str(), &end, 10);
        if (*end != '\0' || i >= plan.points.size()) {
          throw InputError(
              fmt::format("{}: row index '{}' is not a point of this sweep", csv.string(), row[0]));
        }
        for (std::size_t k = 0; k < plan.keys.size(); ++k) {
          if (row[1 + k] != plan.points[i][k]) {
            throw InputError(fmt::format(
                "{}: point {} has {} = {} there, {} in this sweep: another sweep's file",
                csv.string(), i, plan.keys[k], row[1 + k], plan.points[i][k]));
          }
        }
        if (done[i]) {
          throw InputError(fmt::format(
              "{}: point {} is in it twice (two runs wrote it at once?): remove the repeated "
              "rows, or start again",
              csv.string(), i));
        }
        done[i] = true;
      }
    }
  }
  if (std::filesystem::file_size(csv) == 0) write_all(fd, header, csv);

  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < plan.points.size(); ++i) {
    if (!done[i]) todo.push_back(i);
  }
  if (hooks.phase) hooks.phase("points");
  std::mutex mu;
  std::map<std::size_t, std::string> finished;  // rows waiting for the ones before them
  std::size_t next = 0, evaluated = 0;          // next: position in todo to write
  RunHooks inner;
  inner.cancel = hooks.cancel;
  const auto row_of = [&](std::size_t i) {
    return sweep_row(doc, base, plan, options, columns, i, inner);
  };
  // Rows in point order: write every finished row that follows the written ones.
  const auto accept = [&](std::size_t k, std::string line) {
    finished.emplace(k, std::move(line));
    ++evaluated;
    while (!finished.empty() && finished.begin()->first == next) {
      write_all(fd, finished.begin()->second, csv);
      finished.erase(finished.begin());
      ++next;
    }
    if (hooks.progress) hooks.progress(evaluated, todo.size());
  };
  if (world != nullptr) {
    told = true;
    (void)detail::agree_to_start(*world, true);
    // Each rank evaluates one point at a time, on --threads threads (default all cores).
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    detail::distribute_points(
        *world, todo, [&](std::size_t i) { return arena.execute([&] { return row_of(i); }); },
        accept, hooks);
    hooks.check(stopped_message().c_str());
    return evaluated;
  }
  for_each_point(todo.size(), options.threads, hooks, stopped_message().c_str(),
                 [&](std::size_t k) {
                   std::string line = row_of(todo[k]);
                   const std::lock_guard<std::mutex> lock(mu);
                   accept(k, std::move(line));
                 });
  return evaluated;
}

std::size_t run_sweep(const JobDocument& doc, const std::vector<Override>& base,
                      const SweepPlan& plan, const SweepOptions& options,
                      const std::filesystem::path& csv, bool resume, const RunHooks& hooks,
                      const Distributed* world) {
  const bool distributed = world != nullptr && world->size() > 1;
  if (distributed && world->rank() != 0) {  // a worker: points in, rows out
    const Job base_job = doc.build(base);
    const std::vector<std::string> columns = sweep_columns(plan, base_job, options.eval);
    if (!detail::agree_to_start(*world, false)) return 0;  // rank 0 could not start
    RunHooks inner;
    inner.cancel = hooks.cancel;
    tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
    detail::distribute_points(
        *world, {},
        [&](std::size_t i) {
          return arena.execute(
              [&] { return sweep_row(doc, base, plan, options, columns, i, inner); });
        },
        {}, hooks);
    return 0;
  }
  bool told = false;  // rank 0 told the others whether to go
  try {
    return run_sweep_here(doc, base, plan, options, csv, resume, hooks,
                          distributed ? world : nullptr, told);
  } catch (...) {
    if (distributed && !told) (void)detail::agree_to_start(*world, false);
    throw;
  }
}

std::vector<StudyPoint> run_compare(const JobDocument& doc, const std::vector<Override>& base,
                                    const std::vector<Vary>& varies, int threads,
                                    const RunHooks& hooks) {
  if (varies.empty()) {
    throw InputError(
        fmt::format("compare: give at least one key to vary ({}: section.key and its values)",
                    option_name("vary")));
  }
  // Every point's metrics are kept (the sweep streams its rows to a file instead).
  double count = 1;
  for (const Vary& v : varies) count *= static_cast<double>(v.values.size());
  if (count > static_cast<double>(kMaxComparePoints)) {
    throw InputError(fmt::format(
        "compare: the grid has {:.0f} points (limit {}): fewer values, or sweep, which writes "
        "its rows as they come",
        count, kMaxComparePoints));
  }
  const SweepPlan plan = plan_sweep(varies, {}, 0, Sampler::sobol, 0);
  std::vector<StudyPoint> points(plan.points.size());
  for (std::size_t p = 0; p < points.size(); ++p)
    points[p].overrides = point_overrides(base, plan, p);
  hooks.begin("grid");
  SharedProgress progress(hooks, points.size());
  RunHooks inner;  // each point only heeds Ctrl-C; the progress counts points
  inner.cancel = hooks.cancel;
  for_each_point(points.size(), threads, hooks, "interrupted", [&](std::size_t p) {
    StudyPoint& sp = points[p];
    try {
      sp.metrics = analyze_point(doc.build(sp.overrides), inner);
      sp.metrics.series = EngagementSeries{};  // keep the study small
      sp.ok = true;
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      sp.error = e.what();
    }
    progress.add(1);
  });
  return points;
}

}  // namespace trochomill

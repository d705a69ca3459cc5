// `trochomill optimize`: the best job variant under constraints. One objective: NLopt's ISRES
// (a seeded evolution strategy that handles nonlinear constraints) over the numeric variables,
// polished by COBYLA, for each combination of the choice variables. Two or more: pagmo's
// NSGA-II, and the Pareto set of everything evaluated. Every evaluation is a job built from
// the document with the variables' values and run through the sweep's evaluation.
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <nlopt.hpp>

#include "nsga2.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/report.hpp"
#include "trochomill/study.hpp"

namespace trochomill {
namespace {

constexpr double kPenalty = 1e30;  // a failed or infeasible point's objective

// Evaluates points, each once: the values are the cache's key.
class Evaluator {
 public:
  Evaluator(const JobDocument& doc, const std::vector<Override>& base,
            const std::vector<OptVariable>& vars, const std::vector<Constraint>& constraints,
            const OptimizeOptions& o, const AnalysisParts& parts, const RunHooks& hooks)
      : doc_(doc),
        base_(base),
        vars_(vars),
        constraints_(constraints),
        o_(o),
        parts_(parts),
        hooks_(hooks) {
    inner_.cancel = hooks.cancel;
  }

  // The evaluations planned (progress is counted against them).
  void set_total(std::size_t total) { total_ = total; }

  // The TOML value of variable k at x (a number, or a choice index's value).
  std::string value(std::size_t k, double x) const {
    const OptVariable& v = vars_[k];
    if (!v.choices.empty()) {
      const auto i = static_cast<std::size_t>(
          std::clamp(std::floor(x), 0.0, static_cast<double>(v.choices.size() - 1)));
      return v.choices[i];
    }
    x = std::clamp(x, v.lo, v.hi);
    if (v.integer) return fmt::format("{}", std::llround(x));
    // A setting as a program or a control takes it (best.toml is ready for plan): mm to the
    // 4 decimals the programs are written with, mm/min to the 0.001 of their F words,
    // degrees to 0.0001, rpm to 0.1; other keys to 6 significant digits. The point
    // evaluated is the one written, and no 0.30000000000000004 reaches the job.
    const JobKey* jk = find_job_key(v.key);
    const std::string unit = jk != nullptr ? jk->unit : std::string();
    const int places = unit == "mm"        ? 4
                       : unit == "mm/min"  ? 3
                       : unit == "degrees" ? 4
                       : unit == "rpm"     ? 1
                                           : -1;
    // The shortest text of the rounded value (0.9995, not 0.99950000000000006); a range
    // narrower than the rounding keeps x itself (its shortest text), so the point stays in it.
    const double r =
        std::stod(places < 0 ? fmt::format("{:.6g}", x) : fmt::format("{:.{}f}", x, places));
    return fmt::format("{}", r >= v.lo && r <= v.hi ? r : x);
  }

  const OptPoint& at(const std::vector<std::string>& values) {
    {
      const std::lock_guard<std::mutex> lock(mu_);
      const auto it = cache_.find(values);
      if (it != cache_.end()) return it->second;
    }
    hooks_.check("interrupted");
    OptPoint p;
    p.values = values;
    std::vector<Override> o = base_;
    for (std::size_t k = 0; k < vars_.size(); ++k) o.push_back({vars_[k].key, values[k], ""});
    try {
      p.metrics =
          point_metrics(doc_.build(o), o_.eval, o_.cycles, inner_, o_.memory_limit_bytes, parts_);
      p.feasible = true;
      for (const Constraint& c : constraints_) p.feasible = p.feasible && violation(p, c) <= 0;
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception& e) {
      p.error = e.what();
      p.metrics.clear();
    }
    const std::lock_guard<std::mutex> lock(mu_);
    const auto [it, fresh] = cache_.emplace(values, std::move(p));
    // Progress against the planned evaluations (a cached point is no new one; a bound the
    // optimiser may stop short of).
    if (fresh && hooks_.progress) hooks_.progress(cache_.size(), std::max(total_, cache_.size()));
    return it->second;
  }

  // How far a point is from holding c (<= 0: it holds; a missing metric: violated), with a
  // tolerance of 1e-9 of the bound (relative).
  static double violation(const OptPoint& p, const Constraint& c) {
    const auto it = p.metrics.find(c.metric);
    if (it == p.metrics.end()) return kPenalty;
    const double d = c.upper ? it->second - c.value : c.value - it->second;
    return d - 1e-9 * std::abs(c.value);
  }

  // A point found with some of the analysis's parts, given every metric: evaluated again with
  // all of them (the metrics searched on come out the same to the bit). Should that fail (a
  // part left out can fail where the cycle did not), the point keeps the metrics it has.
  void complete(OptPoint& p) const {
    if (parts_.all() || p.metrics.empty()) return;
    std::vector<Override> o = base_;
    for (std::size_t k = 0; k < vars_.size(); ++k) o.push_back({vars_[k].key, p.values[k], ""});
    try {
      p.metrics = point_metrics(doc_.build(o), o_.eval, o_.cycles, inner_, o_.memory_limit_bytes);
    } catch (const Interrupted&) {
      throw;
    } catch (const std::exception&) {
    }
  }

  [[nodiscard]] std::vector<const OptPoint*> all() const {
    std::vector<const OptPoint*> out;
    for (const auto& [k, p] : cache_) out.push_back(&p);
    return out;
  }

 private:
  const JobDocument& doc_;
  const std::vector<Override>& base_;
  const std::vector<OptVariable>& vars_;
  const std::vector<Constraint>& constraints_;
  const OptimizeOptions& o_;
  const AnalysisParts parts_;
  const RunHooks& hooks_;
  RunHooks inner_;
  std::mutex mu_;
  std::map<std::vector<std::string>, OptPoint> cache_;
  std::size_t total_ = 0;
};

// The objective's value to minimise (maximise: its negative); a failed point's penalty.
double goal(const OptPoint& p, const Objective& o) {
  const auto it = p.metrics.find(o.metric);
  if (it == p.metrics.end()) return kPenalty;
  return o.maximize ? -it->second : it->second;
}

bool dominates(const OptPoint& a, const OptPoint& b, const std::vector<Objective>& goals) {
  bool better = false;
  for (const Objective& o : goals) {
    const double fa = goal(a, o), fb = goal(b, o);
    if (fa > fb) return false;
    if (fa < fb) better = true;
  }
  return better;
}

}  // namespace

OptVariable parse_opt_variable(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos) {
    throw InputError(fmt::format("{} '{}': expected section.key=lo:hi or section.key=v1,v2,...",
                                 option_name("variables"), text));
  }
  OptVariable v;
  v.key = trim(text.substr(0, eq));
  const JobKey* k = find_job_key(v.key);
  if (!k) {
    throw InputError(fmt::format("{} {}: no such job key (see `trochomill keys`)",
                                 option_name("variables"), v.key));
  }
  const std::string rest = text.substr(eq + 1);
  if (rest.find(':') != std::string::npos && rest.find(',') == std::string::npos) {
    const SweepRange r = parse_range(text, option_name("variables"));
    if (k->type != "number" && k->type != "integer") {
      throw InputError(
          fmt::format("{} {}: the key is {}, not a number: give its choices as {}=a,b,...",
                      option_name("variables"), v.key, k->type, v.key));
    }
    v.lo = r.lo;
    v.hi = r.hi;
    v.integer = k->type == "integer";
    return v;
  }
  v.choices = parse_vary(text).values;
  if (v.choices.size() < 2) {
    throw InputError(
        fmt::format("{} {}: a choice needs two or more values", option_name("variables"), v.key));
  }
  return v;
}

Constraint parse_constraint(const std::string& text) {
  Constraint c;
  auto op = text.find("<=");
  c.upper = true;
  if (op == std::string::npos) {
    op = text.find(">=");
    c.upper = false;
  }
  if (op == std::string::npos) {
    throw InputError(
        fmt::format("{} '{}': expected METRIC<=VALUE or METRIC>=VALUE, e.g. h_max_mm<=0.05",
                    option_name("subject_to"), text));
  }
  c.metric = trim(text.substr(0, op));
  const std::string v = trim(text.substr(op + 2));
  char* end = nullptr;
  c.value = std::strtod(v.c_str(), &end);
  if (c.metric.empty() || v.empty() || *end != '\0' || !std::isfinite(c.value)) {
    throw InputError(
        fmt::format("{} '{}': expected METRIC<=VALUE or METRIC>=VALUE with a finite number",
                    option_name("subject_to"), text));
  }
  return c;
}

OptimizeResult optimize(const JobDocument& doc, const std::vector<Override>& base,
                        const std::vector<OptVariable>& vars, const std::vector<Objective>& goals,
                        const std::vector<Constraint>& constraints, const OptimizeOptions& o,
                        const RunHooks& hooks) {
  if (vars.empty()) throw InputError("optimize: give at least one " + option_name("variables"));
  if (goals.empty()) {
    throw InputError("optimize: give " + option_name("maximize") + " or " +
                     option_name("minimize") + " METRIC");
  }
  if (o.max_evaluations < 10) {
    throw InputError("optimize: " + option_name("max_evaluations") + " must be at least 10");
  }
  // Every metric named must be one the evaluation gives.
  const Job base_job = doc.build(base);
  const std::vector<std::string> names = metric_names(base_job, o.eval);
  const auto check = [&](const std::string& m, const std::string& option) {
    if (std::find(names.begin(), names.end(), m) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw InputError(fmt::format("{} {}: not a metric of {} {}; these are: {}", option, m,
                                   option_name("eval"), to_string(o.eval), list));
    }
  };
  for (const Objective& g : goals)
    check(g.metric, option_name(g.maximize ? "maximize" : "minimize"));
  for (const Constraint& c : constraints) check(c.metric, option_name("subject_to"));
  for (std::size_t a = 0; a < vars.size(); ++a) {
    for (std::size_t b = a + 1; b < vars.size(); ++b) {
      if (vars[a].key == vars[b].key) {
        throw InputError(fmt::format("{} {}: given twice", option_name("variables"), vars[a].key));
      }
    }
  }

  OptimizeResult r;
  for (const OptVariable& v : vars) r.keys.push_back(v.key);
  // An analysis computes only the parts the goals and constraints read (the floor alone is
  // about half of it); the points reported get all of them (Evaluator::complete).
  std::vector<std::string> named;
  for (const Objective& g : goals) named.push_back(g.metric);
  for (const Constraint& c : constraints) named.push_back(c.metric);
  const AnalysisParts parts =
      o.eval == SweepEval::analyze ? analysis_parts_for(named) : AnalysisParts{};
  Evaluator ev(doc, base, vars, constraints, o, parts, hooks);
  if (hooks.phase) hooks.phase("evaluations");

  if (goals.size() == 1) {
    r.method = "NLopt ISRES (global) then COBYLA (local), per choice combination";
    const Objective& g = goals.front();
    std::vector<std::size_t> numeric, choice;
    for (std::size_t k = 0; k < vars.size(); ++k) {
      (vars[k].choices.empty() ? numeric : choice).push_back(k);
    }
    std::vector<std::size_t> pick(choice.size(), 0);
    std::size_t combinations = 1;
    for (const std::size_t c : choice) combinations *= vars[c].choices.size();
    ev.set_total(combinations * static_cast<std::size_t>(numeric.empty() ? 1 : o.max_evaluations));
    for (;;) {
      // x over every variable: choices fixed at this combination.
      std::vector<double> full(vars.size(), 0.0);
      for (std::size_t c = 0; c < choice.size(); ++c)
        full[choice[c]] = static_cast<double>(pick[c]);
      const auto values_at = [&](const std::vector<double>& x) {
        std::vector<double> all = full;
        for (std::size_t i = 0; i < numeric.size(); ++i) all[numeric[i]] = x[i];
        std::vector<std::string> values;
        for (std::size_t k = 0; k < vars.size(); ++k) values.push_back(ev.value(k, all[k]));
        return values;
      };
      if (numeric.empty()) {
        (void)ev.at(values_at({}));
      } else {
        struct Ctx {
          Evaluator* ev;
          const Objective* g;
          const Constraint* c;
          std::function<std::vector<std::string>(const std::vector<double>&)> values;
        };
        const std::size_t n = numeric.size();
        std::vector<double> lo(n), hi(n), x(n);
        for (std::size_t i = 0; i < n; ++i) {
          lo[i] = vars[numeric[i]].lo;
          hi[i] = vars[numeric[i]].hi;
          x[i] = 0.5 * (lo[i] + hi[i]);
        }
        // The callbacks, as lambdas with their context.
        Ctx obj{&ev, &g, nullptr, {}};
        obj.values = [&](const std::vector<double>& xs) { return values_at(xs); };
        std::vector<Ctx> cons;
        for (const Constraint& c : constraints) cons.push_back({&ev, &g, &c, obj.values});
        // Ctrl-C inside a callback stops NLopt as a forced stop (any other exception there
        // became "nlopt failure", exit 1); the check after the run then says interrupted.
        const auto f = [](unsigned dim, const double* xs, double*, void* data) -> double {
          auto* ctx = static_cast<Ctx*>(data);
          try {
            const OptPoint& p = ctx->ev->at(ctx->values(std::vector<double>(xs, xs + dim)));
            return p.metrics.empty() ? kPenalty : goal(p, *ctx->g);
          } catch (const Interrupted&) {
            throw nlopt::forced_stop();
          }
        };
        const auto gfun = [](unsigned dim, const double* xs, double*, void* data) -> double {
          auto* ctx = static_cast<Ctx*>(data);
          try {
            const OptPoint& p = ctx->ev->at(ctx->values(std::vector<double>(xs, xs + dim)));
            return p.metrics.empty() ? kPenalty : Evaluator::violation(p, *ctx->c);
          } catch (const Interrupted&) {
            throw nlopt::forced_stop();
          }
        };
        const auto run = [&](nlopt::algorithm alg, int evals) {
          nlopt::opt opt(alg, static_cast<unsigned>(n));
          opt.set_lower_bounds(lo);
          opt.set_upper_bounds(hi);
          opt.set_min_objective(static_cast<nlopt::func>(f), &obj);
          for (Ctx& c : cons)
            opt.add_inequality_constraint(static_cast<nlopt::func>(gfun), &c, 0.0);
          opt.set_maxeval(evals);
          opt.set_xtol_rel(1e-7);
          if (alg == nlopt::GN_ISRES)
            opt.set_population(static_cast<unsigned>(std::max(20, 10 * static_cast<int>(n + 1))));
          double fx = 0;
          try {
            (void)opt.optimize(x, fx);
          } catch (const nlopt::roundoff_limited&) {
          } catch (const nlopt::forced_stop&) {
          }
        };
        nlopt::srand(o.seed);
        const int global = o.max_evaluations * 2 / 3;
        run(nlopt::GN_ISRES, global);
        hooks.check("interrupted");
        // Polish from the best feasible point of this combination found so far.
        const OptPoint* best = nullptr;
        for (const OptPoint* p : ev.all()) {
          bool here = true;
          for (std::size_t c = 0; c < choice.size(); ++c) {
            here = here && p->values[choice[c]] == vars[choice[c]].choices[pick[c]];
          }
          if (here && p->feasible && (!best || goal(*p, g) < goal(*best, g))) best = p;
        }
        if (best) {
          for (std::size_t i = 0; i < n; ++i) x[i] = std::stod(best->values[numeric[i]]);
        }
        hooks.check("interrupted");
        run(nlopt::LN_COBYLA, o.max_evaluations - global);
        hooks.check("interrupted");
      }
      hooks.check("interrupted");
      std::size_t c = choice.size();
      while (c > 0) {
        if (++pick[c - 1] < vars[choice[c - 1]].choices.size()) break;
        pick[c - 1] = 0;
        --c;
      }
      if (c == 0) break;
    }
    for (const OptPoint* p : ev.all()) {
      if (p->feasible && (!r.best || goal(*p, g) < goal(*r.best, g))) r.best = *p;
    }
  } else {
    r.method = "pagmo NSGA-II (infeasible points penalised)";
    const int pop = std::max(8, (o.population + 3) / 4 * 4);
    const int generations = std::max(1, o.max_evaluations / pop - 1);
    ev.set_total(static_cast<std::size_t>(pop) * static_cast<std::size_t>(generations + 1));
    // Minimise every goal; a point that fails or breaks a constraint gets the penalty in all
    // of them (the death penalty).
    std::vector<double> lo, hi;
    for (const OptVariable& v : vars) {
      lo.push_back(v.choices.empty() ? v.lo : 0.0);
      hi.push_back(v.choices.empty() ? v.hi : static_cast<double>(v.choices.size()) - 1e-9);
    }
    study_detail::run_nsga2(goals.size(), lo, hi, static_cast<unsigned>(pop),
                            static_cast<unsigned>(generations), static_cast<unsigned>(o.seed),
                            [&](const std::vector<double>& x) {
                              std::vector<std::string> values;
                              for (std::size_t k = 0; k < x.size(); ++k) {
                                values.push_back(ev.value(k, x[k]));
                              }
                              const OptPoint& p = ev.at(values);
                              std::vector<double> f;
                              for (const Objective& g : goals) {
                                f.push_back(p.feasible ? goal(p, g) : kPenalty);
                              }
                              return f;
                            });
    hooks.check("interrupted");
    const auto all = ev.all();
    for (const OptPoint* p : all) {
      if (!p->feasible) continue;
      const bool dominated = std::any_of(all.begin(), all.end(), [&](const OptPoint* q) {
        return q->feasible && dominates(*q, *p, goals);
      });
      if (!dominated) r.pareto.push_back(*p);
    }
    std::sort(r.pareto.begin(), r.pareto.end(), [&](const OptPoint& a, const OptPoint& b) {
      return goal(a, goals.front()) < goal(b, goals.front());
    });
  }
  r.evaluations = ev.all().size();
  {
    std::vector<OptPoint*> reported;
    if (r.best) reported.push_back(&*r.best);
    for (OptPoint& p : r.pareto) reported.push_back(&p);
    tbb::parallel_for(std::size_t{0}, reported.size(),
                      [&](std::size_t i) { ev.complete(*reported[i]); });
    hooks.check("interrupted");
  }
  for (const OptPoint* p : ev.all()) {
    if (p->error.empty()) continue;
    if (r.failed++ == 0) r.first_error = p->error;
  }
  return r;
}

}  // namespace trochomill

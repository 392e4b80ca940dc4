#include "plr/pomdp/pomdpx_reader.hpp"

#include <expat.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>

#include "plr/pomdp/model_io.hpp"
#include "plr/pomdp/text.hpp"

namespace plr::pomdp {
namespace {

struct PomdpxFailure {
  int line;
  std::string what;
};

[[noreturn]] void fail(int line, std::string what) {
  throw PomdpxFailure{line, std::move(what)};
}

// A small element tree built from expat's callbacks.
struct Element {
  std::string name;
  std::vector<std::pair<std::string, std::string>> attributes;
  std::string text;
  int line = 0;
  std::vector<std::unique_ptr<Element>> children;

  const std::string* attribute(std::string_view key) const {
    for (const auto& [k, v] : attributes) {
      if (k == key) return &v;
    }
    return nullptr;
  }
  std::vector<const Element*> all(std::string_view child) const {
    std::vector<const Element*> out;
    for (const auto& c : children) {
      if (c->name == child) out.push_back(c.get());
    }
    return out;
  }
  const Element* first(std::string_view child) const {
    for (const auto& c : children) {
      if (c->name == child) return c.get();
    }
    return nullptr;
  }
  const Element& required(std::string_view child) const {
    const Element* e = first(child);
    if (!e) fail(line, fmt::format("<{}> has no <{}>", name, child));
    return *e;
  }
};

constexpr int kMaxDepth = 32;

struct TreeBuilder {
  XML_Parser parser;
  std::unique_ptr<Element> root;
  std::vector<Element*> stack;
  bool too_deep = false;

  static void on_start(void* self, const XML_Char* name, const XML_Char** attrs) {
    auto& b = *static_cast<TreeBuilder*>(self);
    if (b.stack.size() >= kMaxDepth) {
      b.too_deep = true;
      XML_StopParser(b.parser, XML_FALSE);
      return;
    }
    auto e = std::make_unique<Element>();
    e->name = name;
    e->line = static_cast<int>(XML_GetCurrentLineNumber(b.parser));
    for (int i = 0; attrs[i] != nullptr; i += 2) e->attributes.emplace_back(attrs[i], attrs[i + 1]);
    Element* raw = e.get();
    if (b.stack.empty()) {
      b.root = std::move(e);
    } else {
      b.stack.back()->children.push_back(std::move(e));
    }
    b.stack.push_back(raw);
  }
  static void on_end(void* self, const XML_Char*) {
    static_cast<TreeBuilder*>(self)->stack.pop_back();
  }
  static void on_text(void* self, const XML_Char* s, int len) {
    auto& b = *static_cast<TreeBuilder*>(self);
    if (!b.stack.empty()) b.stack.back()->text.append(s, static_cast<std::size_t>(len));
  }
};

std::unique_ptr<Element> parse_xml(std::string_view text) {
  TreeBuilder b;
  b.parser = XML_ParserCreate(nullptr);
  if (!b.parser) fail(1, "cannot create the XML parser");
  XML_SetUserData(b.parser, &b);
  XML_SetElementHandler(b.parser, &TreeBuilder::on_start, &TreeBuilder::on_end);
  XML_SetCharacterDataHandler(b.parser, &TreeBuilder::on_text);
  const auto status = XML_Parse(b.parser, text.data(), static_cast<int>(text.size()), XML_TRUE);
  const int line = static_cast<int>(XML_GetCurrentLineNumber(b.parser));
  std::string error = status == XML_STATUS_ERROR ? XML_ErrorString(XML_GetErrorCode(b.parser)) : "";
  XML_ParserFree(b.parser);
  if (b.too_deep) fail(line, fmt::format("elements nested deeper than {}", kMaxDepth));
  if (!error.empty()) fail(line, fmt::format("XML: {}", error));
  if (!b.root) fail(1, "no XML element");
  return std::move(b.root);
}

using text::to_number;
using text::words;

enum class Kind { kStatePrev, kStateCurr, kObservation, kAction, kReward };

struct Variable {
  std::string name;
  Kind kind;
  int index = 0;  // among the variables of its kind (prev and curr share)
  std::vector<std::string> values;
  int size() const { return static_cast<int>(values.size()); }
};

// A dense table over variables (the first one varies slowest).
struct Table {
  std::vector<int> vars;
  std::vector<int> sizes;
  std::vector<double> data;
  int line = 0;

  std::size_t offset(const std::vector<int>& value_of) const {
    std::size_t k = 0;
    for (std::size_t i = 0; i < vars.size(); ++i) {
      k = k * static_cast<std::size_t>(sizes[i]) + static_cast<std::size_t>(value_of[i]);
    }
    return k;
  }
};

class Reader {
 public:
  explicit Reader(const ReadLimits& limits) : limits_(limits) {}
  TabularModel read(const Element& root);

 private:
  void read_variables(const Element& e);
  int value_index(const Variable& v, std::string_view token, int line) const;
  // Reads a CondProb (probabilities, `var` last) or a Func (values over parents).
  Table read_table(const Element& e, bool conditional);
  void check_conditional(const Table& t, const char* what) const;

  const ReadLimits& limits_;
  std::vector<Variable> vars_;
  std::unordered_map<std::string, int> by_name_;
  std::vector<int> state_prev_, state_curr_, obs_;  // variable ids in order
  int action_ = -1;
  std::size_t entries_ = 0;
};

void Reader::read_variables(const Element& e) {
  const auto add = [this](Variable v, int line) {
    if (v.name.empty()) fail(line, "a variable without a name");
    if (!by_name_.emplace(v.name, static_cast<int>(vars_.size())).second) {
      fail(line, fmt::format("variable '{}' declared twice", v.name));
    }
    vars_.push_back(std::move(v));
    return static_cast<int>(vars_.size()) - 1;
  };
  const auto values = [this](const Element& v) {
    std::vector<std::string> out;
    if (const Element* en = v.first("ValueEnum")) {
      for (const std::string_view w : words(en->text)) out.emplace_back(w);
      std::vector<std::string> sorted = out;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end()) {
        fail(en->line, "a value is listed twice");
      }
    } else if (const Element* n = v.first("NumValues")) {
      const auto count = to_number(words(n->text).empty() ? "" : words(n->text)[0]);
      if (!count || *count < 1 || *count > limits_.max_states || *count != std::floor(*count)) {
        fail(n->line, fmt::format("NumValues must be an integer in [1, {}]", limits_.max_states));
      }
      for (int i = 0; i < static_cast<int>(*count); ++i) out.push_back(fmt::format("s{}", i));
    } else {
      fail(v.line, fmt::format("<{}> needs <ValueEnum> or <NumValues>", v.name));
    }
    if (out.empty()) fail(v.line, "a variable without values");
    return out;
  };
  for (const auto& c : e.children) {
    const auto name_of = [&c](const char* key) {
      const std::string* s = c->attribute(key);
      if (!s) fail(c->line, fmt::format("<{}> has no {} attribute", c->name, key));
      return *s;
    };
    if (c->name == "StateVar") {
      const auto vals = values(*c);
      const int index = static_cast<int>(state_prev_.size());
      state_prev_.push_back(add({name_of("vnamePrev"), Kind::kStatePrev, index, vals}, c->line));
      state_curr_.push_back(add({name_of("vnameCurr"), Kind::kStateCurr, index, vals}, c->line));
    } else if (c->name == "ObsVar") {
      const int index = static_cast<int>(obs_.size());
      obs_.push_back(add({name_of("vname"), Kind::kObservation, index, values(*c)}, c->line));
    } else if (c->name == "ActionVar") {
      if (action_ >= 0) fail(c->line, "more than one <ActionVar> is not supported");
      action_ = add({name_of("vname"), Kind::kAction, 0, values(*c)}, c->line);
    } else if (c->name == "RewardVar") {
      add({name_of("vname"), Kind::kReward, 0, {}}, c->line);
    } else {
      fail(c->line, fmt::format("unexpected <{}> in <Variable>", c->name));
    }
  }
  if (state_prev_.empty()) fail(e.line, "no <StateVar>");
  if (obs_.empty()) fail(e.line, "no <ObsVar>");
  if (action_ < 0) fail(e.line, "no <ActionVar>");
}

int Reader::value_index(const Variable& v, std::string_view token, int line) const {
  for (int i = 0; i < v.size(); ++i) {
    if (v.values[static_cast<std::size_t>(i)] == token) return i;
  }
  if (const auto k = text::to_index(token); k && *k < v.size()) return static_cast<int>(*k);
  fail(line, fmt::format("'{}' is not a value of '{}'", token, v.name));
}

Table Reader::read_table(const Element& e, bool conditional) {
  Table t;
  t.line = e.line;
  const Element& var = e.required("Var");
  const auto var_names = words(var.text);
  if (var_names.size() != 1) fail(var.line, "<Var> must name one variable");
  const auto parents = words(e.required("Parent").text);
  const auto id = [this](std::string_view name, int line) {
    const auto it = by_name_.find(std::string(name));
    if (it == by_name_.end()) fail(line, fmt::format("unknown variable '{}'", name));
    return it->second;
  };
  for (const std::string_view p : parents) {
    if (p == "null" && parents.size() == 1) break;
    t.vars.push_back(id(p, e.line));
  }
  const int target = id(var_names[0], var.line);
  if (conditional) {
    t.vars.push_back(target);
  } else if (vars_[static_cast<std::size_t>(target)].kind != Kind::kReward) {
    fail(var.line, fmt::format("'{}' is not a <RewardVar>", var_names[0]));
  }
  std::size_t cells = 1;
  for (int v : t.vars) {
    const int n = vars_[static_cast<std::size_t>(v)].size();
    if (n == 0)
      fail(e.line, fmt::format("'{}' cannot be a parent", vars_[static_cast<std::size_t>(v)].name));
    t.sizes.push_back(n);
    cells *= static_cast<std::size_t>(n);
    if (cells > limits_.max_entries)
      fail(e.line, fmt::format("table larger than {} cells", limits_.max_entries));
  }
  entries_ += cells;
  if (entries_ > limits_.max_entries)
    fail(e.line, fmt::format("tables larger than {} cells", limits_.max_entries));
  t.data.assign(cells, 0.0);
  const Element& param = e.required("Parameter");
  if (const std::string* type = param.attribute("type"); type && *type != "TBL") {
    fail(param.line, fmt::format("Parameter type '{}' is not supported (only TBL)", *type));
  }
  const char* table_tag = conditional ? "ProbTable" : "ValueTable";
  for (const Element* entry : param.all("Entry")) {
    const Element& inst = entry->required("Instance");
    const Element& tab = entry->required(table_tag);
    const auto tokens = words(inst.text);
    if (tokens.size() != t.vars.size()) {
      fail(inst.line,
           fmt::format("instance has {} values, expected {}", tokens.size(), t.vars.size()));
    }
    // Fixed values, `*` (every value, same numbers) or `-` (numbers listed).
    std::vector<int> fixed(t.vars.size(), 0);
    std::vector<std::size_t> star, dash;
    std::size_t listed = 1;
    for (std::size_t i = 0; i < tokens.size(); ++i) {
      const Variable& v = vars_[static_cast<std::size_t>(t.vars[i])];
      if (tokens[i] == "*") {
        star.push_back(i);
      } else if (tokens[i] == "-") {
        dash.push_back(i);
        listed *= static_cast<std::size_t>(v.size());
      } else {
        fixed[i] = value_index(v, tokens[i], inst.line);
      }
    }
    const auto numbers = words(tab.text);
    std::vector<double> values;
    if (numbers.size() == 1 && (numbers[0] == "identity" || numbers[0] == "uniform")) {
      if (!conditional) fail(tab.line, fmt::format("'{}' is only for probabilities", numbers[0]));
      values.assign(listed, 0.0);
      if (numbers[0] == "uniform") {
        if (dash.empty() || dash.back() != t.vars.size() - 1) {
          fail(tab.line, "'uniform' needs '-' for the variable itself");
        }
        std::fill(values.begin(), values.end(), 1.0 / t.sizes.back());
      } else {
        if (dash.size() != 2 || t.sizes[dash[0]] != t.sizes[dash[1]]) {
          fail(tab.line, "'identity' needs two '-' of the same size");
        }
        const auto n = static_cast<std::size_t>(t.sizes[dash[0]]);
        for (std::size_t k = 0; k < n; ++k) values[k * n + k] = 1.0;
      }
    } else {
      if (numbers.size() != listed) {
        fail(tab.line, fmt::format("{} numbers, expected {}", numbers.size(), listed));
      }
      for (const std::string_view w : numbers) {
        const auto x = to_number(w);
        if (!x) fail(tab.line, fmt::format("'{}' is not a number", w));
        if (conditional && (*x < 0.0 || *x > 1.0)) {
          fail(tab.line, fmt::format("probability {} is not in [0, 1]", w));
        }
        values.push_back(*x);
      }
    }
    // Every combination of the `*` positions, then the listed `-` values.
    std::size_t star_count = 1;
    for (std::size_t i : star) star_count *= static_cast<std::size_t>(t.sizes[i]);
    std::vector<int> value_of = fixed;
    for (std::size_t sc = 0; sc < star_count; ++sc) {
      std::size_t rest = sc;
      for (auto it = star.rbegin(); it != star.rend(); ++it) {
        value_of[*it] = static_cast<int>(rest % static_cast<std::size_t>(t.sizes[*it]));
        rest /= static_cast<std::size_t>(t.sizes[*it]);
      }
      for (std::size_t k = 0; k < listed; ++k) {
        std::size_t r = k;
        for (auto it = dash.rbegin(); it != dash.rend(); ++it) {
          value_of[*it] = static_cast<int>(r % static_cast<std::size_t>(t.sizes[*it]));
          r /= static_cast<std::size_t>(t.sizes[*it]);
        }
        t.data[t.offset(value_of)] = values[k];
      }
    }
  }
  return t;
}

void Reader::check_conditional(const Table& t, const char* what) const {
  const auto n = static_cast<std::size_t>(t.sizes.back());
  for (std::size_t row = 0; row * n < t.data.size(); ++row) {
    double sum = 0.0;
    for (std::size_t k = 0; k < n; ++k) sum += t.data[row * n + k];
    if (std::abs(sum - 1.0) > 1e-4) {
      // Name the parent values of the row.
      std::string parents;
      std::size_t r = row;
      std::vector<std::string> parts(t.vars.size() - 1);
      for (std::size_t i = t.vars.size() - 1; i-- > 0;) {
        const Variable& v = vars_[static_cast<std::size_t>(t.vars[i])];
        parts[i] = v.name + "=" + v.values[r % static_cast<std::size_t>(v.size())];
        r /= static_cast<std::size_t>(v.size());
      }
      for (const auto& p : parts) parents += (parents.empty() ? "" : ", ") + p;
      fail(t.line, fmt::format("{} P({} | {}) sums to {}, not 1", what,
                               vars_[static_cast<std::size_t>(t.vars.back())].name,
                               parents.empty() ? "-" : parents, sum));
    }
  }
}

TabularModel Reader::read(const Element& root) {
  if (root.name != "pomdpx")
    fail(root.line, fmt::format("root element is <{}>, not <pomdpx>", root.name));
  const Element& disc = root.required("Discount");
  const auto d = to_number(words(disc.text).empty() ? "" : words(disc.text)[0]);
  if (!d || *d < 0.0 || *d > 1.0) fail(disc.line, "<Discount> must be a number in [0, 1]");
  read_variables(root.required("Variable"));

  // Flat sizes.
  std::size_t num_states = 1, num_obs = 1;
  for (int v : state_prev_) {
    num_states *= static_cast<std::size_t>(vars_[static_cast<std::size_t>(v)].size());
    if (num_states > static_cast<std::size_t>(limits_.max_states)) {
      fail(root.required("Variable").line, fmt::format("more than {} states", limits_.max_states));
    }
  }
  for (int v : obs_) {
    num_obs *= static_cast<std::size_t>(vars_[static_cast<std::size_t>(v)].size());
    if (num_obs > static_cast<std::size_t>(limits_.max_observations)) {
      fail(root.required("Variable").line,
           fmt::format("more than {} observations", limits_.max_observations));
    }
  }
  const Variable& action = vars_[static_cast<std::size_t>(action_)];
  if (action.size() > limits_.max_actions) fail(root.required("Variable").line, "too many actions");
  if (num_states * static_cast<std::size_t>(action.size()) > limits_.max_state_actions) {
    fail(root.required("Variable").line,
         fmt::format("states x actions exceeds {} rows", limits_.max_state_actions));
  }
  const int S = static_cast<int>(num_states), A = action.size(), O = static_cast<int>(num_obs);

  // Tables, keyed by their variable.
  const auto tables = [&](const char* section, bool conditional, auto accept) {
    std::vector<Table> out;
    const Element& sec = root.required(section);
    for (const auto& c : sec.children) {
      if (c->name != (conditional ? "CondProb" : "Func")) {
        fail(c->line, fmt::format("unexpected <{}> in <{}>", c->name, section));
      }
      Table t = read_table(*c, conditional);
      for (std::size_t i = 0; i + (conditional ? 1 : 0) < t.vars.size(); ++i) {
        if (!accept(vars_[static_cast<std::size_t>(t.vars[i])].kind)) {
          fail(c->line, fmt::format("'{}' cannot be a parent in <{}>",
                                    vars_[static_cast<std::size_t>(t.vars[i])].name, section));
        }
      }
      if (conditional) check_conditional(t, section);
      out.push_back(std::move(t));
    }
    return out;
  };
  const auto one_per = [&](std::vector<Table>& ts, const std::vector<int>& vars,
                           const char* section) {
    std::vector<const Table*> by_var(vars.size(), nullptr);
    for (const Table& t : ts) {
      const auto it = std::find(vars.begin(), vars.end(), t.vars.back());
      if (it == vars.end()) {
        fail(t.line, fmt::format("'{}' does not belong in <{}>",
                                 vars_[static_cast<std::size_t>(t.vars.back())].name, section));
      }
      auto& slot = by_var[static_cast<std::size_t>(it - vars.begin())];
      if (slot)
        fail(t.line, fmt::format("'{}' has two tables",
                                 vars_[static_cast<std::size_t>(t.vars.back())].name));
      slot = &t;
    }
    for (std::size_t i = 0; i < vars.size(); ++i) {
      if (!by_var[i]) {
        fail(root.required(section).line,
             fmt::format("no table for '{}' in <{}>", vars_[static_cast<std::size_t>(vars[i])].name,
                         section));
      }
    }
    return by_var;
  };
  auto initial = tables("InitialStateBelief", true, [](Kind k) { return k == Kind::kStatePrev; });
  auto transition = tables("StateTransitionFunction", true,
                           [](Kind k) { return k == Kind::kStatePrev || k == Kind::kAction; });
  auto observation = tables("ObsFunction", true,
                            [](Kind k) { return k == Kind::kStateCurr || k == Kind::kAction; });
  auto reward = tables("RewardFunction", false, [](Kind k) {
    return k == Kind::kStatePrev || k == Kind::kStateCurr || k == Kind::kAction;
  });
  // Initial beliefs may name either the prev or the curr variable.
  for (Table& t : initial) {
    const Variable& v = vars_[static_cast<std::size_t>(t.vars.back())];
    if (v.kind == Kind::kStateCurr) t.vars.back() = state_prev_[static_cast<std::size_t>(v.index)];
    if (t.vars.size() != 1) fail(t.line, "initial beliefs with parents are not supported");
  }
  const auto init_by = one_per(initial, state_prev_, "InitialStateBelief");
  const auto trans_by = one_per(transition, state_curr_, "StateTransitionFunction");
  const auto obs_by = one_per(observation, obs_, "ObsFunction");

  const std::size_t k = state_prev_.size();
  // Values of every state variable in a flat state (first variable slowest).
  const auto decode = [&](int s, std::vector<int>& out) {
    out.resize(k);
    for (std::size_t i = k; i-- > 0;) {
      const int n = vars_[static_cast<std::size_t>(state_prev_[i])].size();
      out[i] = s % n;
      s /= n;
    }
  };
  // Values of every variable (by id) for a table lookup.
  std::vector<int> value(vars_.size(), 0);
  const auto lookup = [&](const Table& t, std::vector<int>& scratch) {
    scratch.resize(t.vars.size());
    for (std::size_t i = 0; i < t.vars.size(); ++i)
      scratch[i] = value[static_cast<std::size_t>(t.vars[i])];
    return t.offset(scratch);
  };

  TabularModel m(S, A, O);
  m.set_discount(*d);
  std::vector<int> sv, scratch;
  // The joint distribution of independent variables given the values set in
  // `value`: one table per variable, the first variable slowest, so the
  // result comes out sorted by flat index.
  std::vector<std::pair<int, double>> row, grown;
  const auto product = [&](const std::vector<const Table*>& tables, int line) {
    row.assign(1, {0, 1.0});
    for (const Table* t : tables) {
      const int n = t->sizes.back();
      value[static_cast<std::size_t>(t->vars.back())] = 0;
      const std::size_t base = lookup(*t, scratch);
      grown.clear();
      for (const auto& [partial, p] : row) {
        for (int x = 0; x < n; ++x) {
          const double q = t->data[base + static_cast<std::size_t>(x)];
          if (q > 0.0) grown.emplace_back(partial * n + x, p * q);
        }
      }
      row.swap(grown);
    }
    entries_ += row.size();
    if (entries_ > limits_.max_entries) fail(line, "too many table entries");
  };
  for (int a = 0; a < A; ++a) {
    value[static_cast<std::size_t>(action_)] = a;
    for (int s = 0; s < S; ++s) {
      decode(s, sv);
      // Transitions from s, then observations on arriving in s (set after:
      // the transition tables use the current-state slots as scratch).
      for (std::size_t i = 0; i < k; ++i) value[static_cast<std::size_t>(state_prev_[i])] = sv[i];
      product(trans_by, root.required("StateTransitionFunction").line);
      for (const auto& [next, p] : row) m.mutable_transitions(a, s).push_back({next, p, 0.0});
      for (std::size_t i = 0; i < k; ++i) value[static_cast<std::size_t>(state_curr_[i])] = sv[i];
      product(obs_by, root.required("ObsFunction").line);
      for (const auto& [o, p] : row) m.mutable_observations(a, s).push_back({o, p});
    }
  }
  // Rewards: the sum of every reward table, per transition.
  for (int a = 0; a < A; ++a) {
    value[static_cast<std::size_t>(action_)] = a;
    for (int s = 0; s < S; ++s) {
      decode(s, sv);
      for (std::size_t i = 0; i < k; ++i) value[static_cast<std::size_t>(state_prev_[i])] = sv[i];
      for (Transition& tr : m.mutable_transitions(a, s)) {
        decode(tr.next, sv);
        for (std::size_t i = 0; i < k; ++i) value[static_cast<std::size_t>(state_curr_[i])] = sv[i];
        double r = 0.0;
        for (const Table& t : reward) r += t.data[lookup(t, scratch)];
        tr.reward = r;
      }
    }
  }
  // Initial belief: the product of the per-variable distributions.
  product(init_by, root.required("InitialStateBelief").line);
  Belief b;
  for (const auto& [s, p] : row) b.add(s, p);
  b.normalize();
  m.set_initial_belief(std::move(b));

  // Names: values joined by ',' (states), action values, observation values.
  for (int s = 0; s < S; ++s) {
    decode(s, sv);
    std::string name;
    for (std::size_t i = 0; i < k; ++i) {
      if (i) name += ',';
      name +=
          vars_[static_cast<std::size_t>(state_prev_[i])].values[static_cast<std::size_t>(sv[i])];
    }
    m.state_names.push_back(std::move(name));
  }
  m.action_names = action.values;
  for (int o = 0; o < O; ++o) {
    std::string name;
    int rest = o;
    std::vector<std::string> parts(obs_.size());
    for (std::size_t i = obs_.size(); i-- > 0;) {
      const Variable& v = vars_[static_cast<std::size_t>(obs_[i])];
      parts[i] = v.values[static_cast<std::size_t>(rest % v.size())];
      rest /= v.size();
    }
    for (std::size_t i = 0; i < parts.size(); ++i) name += (i ? "," : "") + parts[i];
    m.observation_names.push_back(std::move(name));
  }
  m.finish();
  return m;
}

}  // namespace

plr::Expected<TabularModel> parse_pomdpx(std::string_view text, const std::string& origin,
                                         const ReadLimits& limits) {
  if (text.size() > limits.max_file_bytes ||
      text.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1: file larger than {} bytes", origin,
                                                        limits.max_file_bytes));
  }
  try {
    const auto root = parse_xml(text);
    Reader reader(limits);
    return reader.read(*root);
  } catch (const PomdpxFailure& f) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:{}: {}", origin, f.line, f.what));
  } catch (const std::bad_alloc&) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1: out of memory", origin));
  }
}

plr::Expected<TabularModel> read_pomdpx(const std::filesystem::path& file,
                                        const ReadLimits& limits) {
  auto text = read_text_file(file, limits.max_file_bytes);
  if (!text) return text.error();
  return parse_pomdpx(*text, file.string(), limits);
}

}  // namespace plr::pomdp

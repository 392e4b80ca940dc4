#include "plr/pomdp/cassandra_reader.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>

#include "plr/pomdp/model_io.hpp"
#include "plr/pomdp/text.hpp"

namespace plr::pomdp {
namespace {

using text::to_index;
using text::to_number;
using text::Token;

// Thrown inside the parser only; the public functions turn it into an Error.
struct ParseFailure {
  int line, column;
  std::string what;
};

constexpr int kAll = -1;  // a `*` wildcard

struct Names {
  const char* kind;  // "state", "action", "observation"
  std::vector<std::string> names;
  std::unordered_map<std::string, int> index;
  int size() const { return static_cast<int>(names.size()); }
};

// One R line: later lines override earlier ones where they overlap.
struct RewardRule {
  int action, state, next, observation;
  double value;
};

class Parser {
 public:
  Parser(std::string_view text, const ReadLimits& limits)
      : tokens_(text::tokenize(text, {.colon_tokens = true, .comments = true})), limits_(limits) {}

  TabularModel parse();

 private:
  [[noreturn]] void fail(const Token& t, std::string what) const {
    throw ParseFailure{t.line, t.column, std::move(what)};
  }
  [[noreturn]] void fail_here(std::string what) const {
    if (pos_ < tokens_.size()) fail(tokens_[pos_], std::move(what));
    fail(end_token(), std::move(what));
  }
  Token end_token() const {
    return tokens_.empty() ? Token{} : Token{{}, tokens_.back().line, tokens_.back().column};
  }
  bool at_end() const { return pos_ >= tokens_.size(); }
  const Token& peek() const { return tokens_[pos_]; }
  bool peek_is(std::string_view s, std::size_t ahead = 0) const {
    return pos_ + ahead < tokens_.size() && tokens_[pos_ + ahead].text == s;
  }
  const Token& next(const char* expected) {
    if (at_end()) fail(end_token(), fmt::format("unexpected end of file, expected {}", expected));
    return tokens_[pos_++];
  }
  void expect_colon() {
    const Token& t = next("':'");
    if (t.text != ":") fail(t, fmt::format("expected ':', found '{}'", t.text));
  }
  double number(const char* what) {
    const Token& t = next(what);
    const auto v = to_number(t.text);
    if (!v) fail(t, fmt::format("expected {}, found '{}'", what, t.text));
    return *v;
  }
  double probability() {
    const Token& t = tokens_[std::min(pos_, tokens_.size() - 1)];
    const double p = number("a probability");
    if (p < 0.0 || p > 1.0) fail(t, fmt::format("probability {} is not in [0, 1]", t.text));
    return p;
  }
  bool statement_start(std::size_t i) const;
  void declare(Names& names, int limit);
  int ref(const Names& names);
  std::vector<int> expand(const Names& names, int r) const {
    if (r != kAll) return {r};
    std::vector<int> all(static_cast<std::size_t>(names.size()));
    for (int k = 0; k < names.size(); ++k) all[static_cast<std::size_t>(k)] = k;
    return all;
  }
  void need_sizes(const Token& t) const {
    if (!model_) fail(t, "states, actions and observations must be declared before this line");
  }
  void make_model(const Token& t);
  void parse_start(const Token& keyword);
  void parse_table(const Token& keyword, bool transitions);
  void parse_reward(const Token& keyword);
  void count_entries(std::size_t n, const Token& t) {
    entries_ += n;
    if (entries_ > limits_.max_entries) {
      fail(t, fmt::format("more than {} table entries", limits_.max_entries));
    }
  }
  template <class Row>
  void set(Row& row, int key, double p, const Token& t);
  void finish_rows();
  void resolve_rewards();

  std::vector<Token> tokens_;
  std::size_t pos_ = 0;
  const ReadLimits& limits_;
  std::size_t entries_ = 0;
  double discount_ = -1.0;
  bool cost_ = false;
  Names states_{"state", {}, {}}, actions_{"action", {}, {}}, observations_{"observation", {}, {}};
  std::optional<TabularModel> model_;
  std::optional<Belief> start_;
  std::vector<Token> t_where_, o_where_;  // the last line that set each row
  std::vector<RewardRule> rules_;
  std::vector<Token> rule_where_;
};

bool Parser::statement_start(std::size_t i) const {
  if (i + 1 >= tokens_.size()) return false;
  const std::string_view t = tokens_[i].text;
  const std::string_view n = tokens_[i + 1].text;
  if (t == "start" && (n == "include" || n == "exclude")) return true;
  if (n != ":") return false;
  return t == "discount" || t == "values" || t == "states" || t == "actions" ||
         t == "observations" || t == "start" || t == "T" || t == "O" || t == "R";
}

void Parser::declare(Names& names, int limit) {
  const Token& first = next("a count or names");
  if (!names.names.empty()) fail(first, fmt::format("{}s declared twice", names.kind));
  std::vector<Token> list{first};
  while (!at_end() && !statement_start(pos_)) list.push_back(tokens_[pos_++]);
  if (list.size() == 1) {
    if (const auto n = to_index(first.text)) {
      if (*n == 0 || *n > limit) {
        fail(first, fmt::format("{} count {} is not in [1, {}]", names.kind, first.text, limit));
      }
      for (long k = 0; k < *n; ++k) {
        names.names.push_back(std::to_string(k));
        names.index.emplace(names.names.back(), static_cast<int>(k));
      }
      return;
    }
  }
  if (static_cast<long>(list.size()) > limit) {
    fail(first, fmt::format("more than {} {}s", limit, names.kind));
  }
  for (const Token& t : list) {
    if (t.text == "*" || to_number(t.text)) {
      fail(t, fmt::format("'{}' is not a valid {} name", t.text, names.kind));
    }
    std::string name(t.text);
    if (!names.index.emplace(name, names.size()).second) {
      fail(t, fmt::format("{} '{}' declared twice", names.kind, t.text));
    }
    names.names.push_back(std::move(name));
  }
}

int Parser::ref(const Names& names) {
  const Token& t = next(names.kind);
  if (t.text == "*") return kAll;
  if (const auto it = names.index.find(std::string(t.text)); it != names.index.end()) {
    return it->second;
  }
  if (const auto n = to_index(t.text)) {
    if (*n < names.size()) return static_cast<int>(*n);
    fail(t,
         fmt::format("{} index {} out of range (there are {})", names.kind, t.text, names.size()));
  }
  fail(t, fmt::format("unknown {} '{}'", names.kind, t.text));
}

void Parser::make_model(const Token& t) {
  if (model_) return;
  if (states_.names.empty() || actions_.names.empty() || observations_.names.empty()) {
    fail(t, "states, actions and observations must be declared before this line");
  }
  const std::size_t rows =
      static_cast<std::size_t>(states_.size()) * static_cast<std::size_t>(actions_.size());
  if (rows > limits_.max_state_actions) {
    fail(t, fmt::format("{} states x {} actions exceeds the limit of {} rows", states_.size(),
                        actions_.size(), limits_.max_state_actions));
  }
  model_.emplace(states_.size(), actions_.size(), observations_.size());
  t_where_.assign(rows, Token{});
  o_where_.assign(rows, Token{});
}

template <class Row>
void Parser::set(Row& row, int key, double p, const Token& t) {
  using Entry = typename Row::value_type;
  const auto key_of = [](const Entry& e) {
    if constexpr (std::is_same_v<Entry, Transition>) {
      return e.next;
    } else {
      return e.observation;
    }
  };
  auto it = std::lower_bound(row.begin(), row.end(), key,
                             [&](const Entry& e, int k) { return key_of(e) < k; });
  if (it != row.end() && key_of(*it) == key) {
    if (p == 0.0) {
      row.erase(it);
    } else {
      it->probability = p;
    }
  } else if (p != 0.0) {
    count_entries(1, t);
    Entry e{};
    if constexpr (std::is_same_v<Entry, Transition>) {
      e.next = key;
    } else {
      e.observation = key;
    }
    e.probability = p;
    row.insert(it, e);
  }
}

void Parser::parse_start(const Token& keyword) {
  make_model(keyword);
  if (start_) fail(keyword, "start declared twice");
  const int n = states_.size();
  Belief b;
  if (peek_is("include") || peek_is("exclude")) {
    const bool include = peek().text == "include";
    ++pos_;
    expect_colon();
    std::vector<char> in(static_cast<std::size_t>(n), include ? 0 : 1);
    do {
      const int s = ref(states_);
      for (int k : expand(states_, s)) in[static_cast<std::size_t>(k)] = include ? 1 : 0;
    } while (!at_end() && !statement_start(pos_));
    for (int s = 0; s < n; ++s) {
      if (in[static_cast<std::size_t>(s)]) b.add(s, 1.0);
    }
  } else {
    expect_colon();
    std::size_t count = 0;
    while (pos_ + count < tokens_.size() && !statement_start(pos_ + count)) ++count;
    if (peek_is("uniform")) {
      ++pos_;
      for (int s = 0; s < n; ++s) b.add(s, 1.0);
    } else if (count == static_cast<std::size_t>(n) && to_number(peek().text)) {
      for (int s = 0; s < n; ++s) b.add(s, probability());
    } else {
      const int s = ref(states_);
      for (int k : expand(states_, s)) b.add(k, 1.0);
    }
  }
  if (!(b.normalize() > 0.0)) fail(keyword, "the start belief has no probability mass");
  if (std::abs(b.total_weight() - 1.0) > 1e-6) fail(keyword, "bad start belief");
  start_ = std::move(b);
}

// T and O lines have one shape: rows of a table per action and state (the
// state before for T, the state reached for O), columns the next states (T)
// or the observations (O).
//   X: a : s : column p   one entry
//   X: a : s  p ... | uniform   one row
//   X: a  p ... | identity | uniform   the whole matrix
void Parser::parse_table(const Token& keyword, bool transitions) {
  make_model(keyword);
  const int n = states_.size();
  const Names& columns = transitions ? states_ : observations_;
  const int nc = columns.size();
  const int a = ref(actions_);
  TabularModel& m = *model_;
  std::vector<Token>& where = transitions ? t_where_ : o_where_;
  const auto touch = [&](int act, int s) {
    where[static_cast<std::size_t>(act) * static_cast<std::size_t>(n) +
          static_cast<std::size_t>(s)] = keyword;
  };
  // Sets one entry (later lines override earlier ones).
  const auto put = [&](int act, int s, int column, double p) {
    if (transitions) {
      set(m.mutable_transitions(act, s), column, p, keyword);
    } else {
      set(m.mutable_observations(act, s), column, p, keyword);
    }
  };
  if (peek_is(":")) {
    ++pos_;
    const int s = ref(states_);
    std::vector<std::pair<int, double>> entries;  // column, probability
    if (peek_is(":")) {
      ++pos_;
      const int column = ref(columns);
      const double p = probability();
      for (int c : expand(columns, column)) entries.emplace_back(c, p);
    } else if (peek_is("uniform")) {
      ++pos_;
      for (int c = 0; c < nc; ++c) entries.emplace_back(c, 1.0 / nc);
    } else {
      for (int c = 0; c < nc; ++c) entries.emplace_back(c, probability());
    }
    for (int act : expand(actions_, a)) {
      for (int from : expand(states_, s)) {
        for (const auto& [c, p] : entries) put(act, from, c, p);
        touch(act, from);
      }
    }
    return;
  }
  // The whole matrix: each row is replaced.
  const bool identity = peek_is("identity"), uniform = peek_is("uniform");
  if (identity && nc != n) {
    fail(peek(), "an identity observation matrix needs as many observations as states");
  }
  count_entries(expand(actions_, a).size() * static_cast<std::size_t>(n) *
                    static_cast<std::size_t>(identity ? 1 : nc),
                keyword);
  std::vector<double> matrix;
  if (identity || uniform) {
    ++pos_;
  } else {
    matrix.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(nc));
    for (double& p : matrix) p = probability();
  }
  for (int act : expand(actions_, a)) {
    for (int from = 0; from < n; ++from) {
      const auto value = [&](int c) {
        if (identity) return c == from ? 1.0 : 0.0;
        if (uniform) return 1.0 / nc;
        return matrix[static_cast<std::size_t>(from) * static_cast<std::size_t>(nc) +
                      static_cast<std::size_t>(c)];
      };
      if (transitions) {
        auto& r = m.mutable_transitions(act, from);
        r.clear();
        for (int c = 0; c < nc; ++c) {
          if (value(c) > 0.0) r.push_back({c, value(c), 0.0});
        }
      } else {
        auto& r = m.mutable_observations(act, from);
        r.clear();
        for (int c = 0; c < nc; ++c) {
          if (value(c) > 0.0) r.push_back({c, value(c)});
        }
      }
      touch(act, from);
    }
  }
}

void Parser::parse_reward(const Token& keyword) {
  make_model(keyword);
  const int n = states_.size(), no = observations_.size();
  const int a = ref(actions_);
  expect_colon();
  const int s = ref(states_);
  const auto add = [&](int s2, int o, double v) {
    count_entries(1, keyword);
    rules_.push_back({a, s, s2, o, cost_ ? -v : v});
    rule_where_.push_back(keyword);
  };
  if (!peek_is(":")) {
    // A matrix over next states and observations.
    for (int s2 = 0; s2 < n; ++s2) {
      for (int o = 0; o < no; ++o) add(s2, o, number("a reward"));
    }
    return;
  }
  ++pos_;
  const int s2 = ref(states_);
  if (!peek_is(":")) {
    for (int o = 0; o < no; ++o) add(s2, o, number("a reward"));
    return;
  }
  ++pos_;
  const int o = ref(observations_);
  add(s2, o, number("a reward"));
}

void Parser::finish_rows() {
  TabularModel& m = *model_;
  const int n = states_.size();
  const auto check = [&](auto& row, const Token& where, const char* table, int a, int s) {
    double sum = 0.0;
    for (const auto& e : row) sum += e.probability;
    if (row.empty()) {
      fail(end_token(), fmt::format("{} has no entries for action '{}' in state '{}'", table,
                                    actions_.names[static_cast<std::size_t>(a)],
                                    states_.names[static_cast<std::size_t>(s)]));
    }
    if (std::abs(sum - 1.0) > 1e-4) {
      fail(where, fmt::format("{} probabilities for action '{}' in state '{}' sum to {}, not 1",
                              table, actions_.names[static_cast<std::size_t>(a)],
                              states_.names[static_cast<std::size_t>(s)], sum));
    }
    for (auto& e : row) e.probability /= sum;
  };
  for (int a = 0; a < actions_.size(); ++a) {
    for (int s = 0; s < n; ++s) {
      const std::size_t r =
          static_cast<std::size_t>(a) * static_cast<std::size_t>(n) + static_cast<std::size_t>(s);
      check(m.mutable_transitions(a, s), t_where_[r], "T", a, s);
      check(m.mutable_observations(a, s), o_where_[r], "O", a, s);
    }
  }
}

void Parser::resolve_rewards() {
  TabularModel& m = *model_;
  const int n = states_.size();
  // Rules by (action, state) with wildcards kept apart, so each transition
  // looks only at the rules that can match it; the last matching rule wins.
  std::unordered_map<std::int64_t, std::vector<std::uint32_t>> by_key;
  const auto key = [n](int a, int s) {
    return static_cast<std::int64_t>(a + 1) * (static_cast<std::int64_t>(n) + 1) + (s + 1);
  };
  for (std::uint32_t i = 0; i < rules_.size(); ++i) {
    by_key[key(rules_[i].action, rules_[i].state)].push_back(i);
  }
  const std::vector<std::uint32_t> none;
  const auto find = [&](int a, int s) -> const std::vector<std::uint32_t>& {
    const auto it = by_key.find(key(a, s));
    return it == by_key.end() ? none : it->second;
  };
  for (int a = 0; a < actions_.size(); ++a) {
    for (int s = 0; s < n; ++s) {
      const std::vector<std::uint32_t>* lists[4] = {&find(a, s), &find(a, kAll), &find(kAll, s),
                                                    &find(kAll, kAll)};
      if (lists[0]->empty() && lists[1]->empty() && lists[2]->empty() && lists[3]->empty()) {
        continue;
      }
      for (Transition& t : m.mutable_transitions(a, s)) {
        double expected = 0.0;
        for (const ObsProb& o : m.observations(a, t.next)) {
          std::int64_t best = -1;
          for (const auto* list : lists) {
            // Each list is in file order: scan from its end.
            for (auto it = list->rbegin(); it != list->rend(); ++it) {
              const RewardRule& r = rules_[*it];
              if ((r.next == kAll || r.next == t.next) &&
                  (r.observation == kAll || r.observation == o.observation)) {
                best = std::max<std::int64_t>(best, *it);
                break;
              }
            }
          }
          if (best >= 0) expected += o.probability * rules_[static_cast<std::size_t>(best)].value;
        }
        t.reward = expected;
      }
    }
  }
}

TabularModel Parser::parse() {
  while (!at_end()) {
    const Token& keyword = tokens_[pos_];
    if (!statement_start(pos_)) {
      fail(keyword, fmt::format("expected a statement (discount:, values:, states:, actions:, "
                                "observations:, start:, T:, O:, R:), found '{}'",
                                keyword.text));
    }
    ++pos_;
    const std::string_view k = keyword.text;
    if (k == "start") {
      parse_start(keyword);
      continue;
    }
    expect_colon();
    if (k == "discount") {
      const Token& t = peek();
      discount_ = number("a discount factor");
      if (discount_ < 0.0 || discount_ > 1.0) fail(t, "the discount must be in [0, 1]");
    } else if (k == "values") {
      const Token& t = next("reward or cost");
      if (t.text != "reward" && t.text != "cost") {
        fail(t, fmt::format("values must be 'reward' or 'cost', found '{}'", t.text));
      }
      if (!rules_.empty()) fail(t, "values: must come before the first R: line");
      cost_ = t.text == "cost";
    } else if (k == "states") {
      if (model_) fail(keyword, "states declared after the tables");
      declare(states_, limits_.max_states);
    } else if (k == "actions") {
      if (model_) fail(keyword, "actions declared after the tables");
      declare(actions_, limits_.max_actions);
    } else if (k == "observations") {
      if (model_) fail(keyword, "observations declared after the tables");
      declare(observations_, limits_.max_observations);
    } else if (k == "T" || k == "O") {
      parse_table(keyword, k == "T");
    } else {
      parse_reward(keyword);
    }
  }
  if (discount_ < 0.0) fail(tokens_.empty() ? Token{} : tokens_.front(), "no discount: line");
  if (!model_) fail(end_token(), "no T: and O: tables");
  finish_rows();
  resolve_rewards();
  TabularModel& m = *model_;
  m.set_discount(discount_);
  if (!start_) {
    Belief b;
    for (int s = 0; s < states_.size(); ++s) b.add(s, 1.0);
    b.normalize();
    start_ = std::move(b);
  }
  m.set_initial_belief(std::move(*start_));
  m.state_names = std::move(states_.names);
  m.action_names = std::move(actions_.names);
  m.observation_names = std::move(observations_.names);
  m.finish();
  return std::move(m);
}

}  // namespace

plr::Expected<TabularModel> parse_cassandra(std::string_view text, const std::string& origin,
                                            const ReadLimits& limits) {
  if (text.size() > limits.max_file_bytes) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1:1: file larger than {} bytes", origin,
                                                        limits.max_file_bytes));
  }
  try {
    Parser parser(text, limits);
    return parser.parse();
  } catch (const ParseFailure& f) {
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}:{}:{}: {}", origin, f.line, f.column, f.what));
  } catch (const std::bad_alloc&) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1:1: out of memory", origin));
  }
}

plr::Expected<TabularModel> read_cassandra(const std::filesystem::path& file,
                                           const ReadLimits& limits) {
  auto text = read_text_file(file, limits.max_file_bytes);
  if (!text) return text.error();
  return parse_cassandra(*text, file.string(), limits);
}

}  // namespace plr::pomdp

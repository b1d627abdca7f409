#pragma once
/// Typed parameter tables: each parameter of a plain settings struct declared once, with key, group, unit,
/// range, default, description and liveness, and one visit over its value type that the GUI panel, the JSON
/// readers, the presets, the command line and the session all use (after SPlisHSPlasH's `initParameters`,
/// without its global registry). The simulation's table is sim::ParamTable (sim/params.h); the renderer's is
/// render::RenderSettingsTable (render/render_settings.h).

#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace fp::sim {

/// Kind of value a parameter holds.
enum class ParamKind {
  Number,   ///< double or float
  Integer,  ///< int
  Boolean,  ///< bool
  Vector3,  ///< std::array<double, 3>, the range applies to each component
  Seed,     ///< std::uint64_t
  Choice,   ///< an enum, named by `ParamEntry::choices`
};

/// The value of a Choice parameter as the visit hands it out: an index into `names`.
struct Choice {
  int index = 0;                                    ///< [0, names->size())
  const std::vector<std::string>* names = nullptr;  ///< the enum's names, in enum order
  /// name of the current value
  const std::string& name() const { return (*names)[std::size_t(index)]; }
};

/// How a Choice member is read and written: through its enum's integer value.
template <class S>
struct ChoiceMember {
  int (*get)(const S&);  ///< the enum's value as an index
  void (*set)(S&, int);  ///< sets the enum from an index
};

/// A parameter value of any kind, as stored for a default (Choice: the index).
using ParamValue = std::variant<double, float, int, bool, std::uint64_t, std::array<double, 3>, Choice>;

/// Declaration of one parameter of the struct S.
template <class S>
struct ParamEntry {
  /// where the value lives in S
  using Member = std::variant<double S::*, float S::*, int S::*, bool S::*, std::uint64_t S::*,
                              std::array<double, 3> S::*, ChoiceMember<S>>;
  std::string key;                   ///< file and command-line key, snake_case
  std::string group;                 ///< panel group
  std::string unit;                  ///< SI unit or "-"
  ParamKind kind;                    ///< value kind, follows from the member's type
  double min;                        ///< smallest allowed value (each component for Vector3; 0 for Choice)
  double max;                        ///< largest allowed value (each component for Vector3)
  std::string description;           ///< one line
  bool live;                         ///< may change while the simulation runs
  Member member;                     ///< where the value lives
  ParamValue defaultValue;           ///< the default, of the member's type
  std::vector<std::string> choices;  ///< Choice: names in enum order; else empty
};

/// Calls f(value&) with a reference to the parameter's value in `s`, typed double, float, int, bool,
/// std::uint64_t, std::array<double, 3> or Choice (stored back when f returns: edit it, call no setter).
template <class S, class F>
decltype(auto) visit(const ParamEntry<S>& e, S& s, F&& f) {
  return std::visit(
      [&](auto m) -> decltype(auto) {
        if constexpr (std::is_same_v<decltype(m), ChoiceMember<S>>) {
          Choice c{m.get(s), &e.choices};
          struct StoreBack {
            Choice& c;
            S& s;
            void (*set)(S&, int);
            ~StoreBack() { set(s, c.index); }
          } store{c, s, m.set};
          return f(c);
        } else {
          return f(s.*m);
        }
      },
      e.member);
}

/// Calls f(const value&) with the parameter's value in `s` (types as for the mutable visit).
template <class S, class F>
decltype(auto) visit(const ParamEntry<S>& e, const S& s, F&& f) {
  return std::visit(
      [&](auto m) -> decltype(auto) {
        if constexpr (std::is_same_v<decltype(m), ChoiceMember<S>>) {
          const Choice c{m.get(s), &e.choices};
          return f(c);
        } else {
          return f(s.*m);
        }
      },
      e.member);
}

/// Overload set for visits: visit(e, s, Overloaded{[](double&) {...}, [](bool&) {...}, ...}).
template <class... Fs>
struct Overloaded : Fs... {
  using Fs::operator()...;
};
template <class... Fs>
Overloaded(Fs...) -> Overloaded<Fs...>;

/// Levenshtein distance between two names.
std::size_t editDistance(std::string_view a, std::string_view b);
/// " (did you mean x?)" when one of `known` is within two edits of `name`, else empty.
std::string didYouMean(std::string_view name, const std::vector<std::string>& known);
/// Joins names as "a, b or c".
std::string joinNames(const std::vector<std::string>& names);
/// A number as the messages write it: 6 significant digits ("0.001", "4.29497e+09").
std::string formatNumber(double v);

/// Table-independent parts of ParamTableOf: value checks and text conversion shared by every table.
namespace param_detail {
/// "" or why `v` may not be stored in a parameter of `kind` ranging over [min, max] named `key`.
std::string checkScalar(const std::string& key, ParamKind kind, double min, double max, double v);
/// Parses text as a number of `kind` (Boolean: true/false/on/off/yes/no/1/0); "" or the error.
std::string parseScalar(const std::string& key, ParamKind kind, std::string_view text, double& out);
/// Parses "x,y,z" (brackets and spaces allowed); "" or the error.
std::string parseVec3(const std::string& key, std::string_view text, std::array<double, 3>& out);
/// Index of `text` in `names`; "" or the error naming them.
std::string parseChoice(const std::string& key, const std::vector<std::string>& names, std::string_view text,
                        int& out);
/// A number in the fewest significant digits (at least 6) that read back to the same double.
std::string formatValue(double v);
}  // namespace param_detail

/// A table of the parameters of the struct S, in panel order; immutable once built by a derived table.
template <class S>
class ParamTableOf {
 public:
  using Entry = ParamEntry<S>;

  /// every parameter, in panel order
  const std::vector<Entry>& entries() const { return m_entries; }
  /// the declaration named `key`, or nullptr
  const Entry* find(std::string_view key) const {
    for (const Entry& e : m_entries) {
      if (e.key == key)
        return &e;
    }
    return nullptr;
  }
  /// the declaration named `key`; throws std::out_of_range when there is none
  const Entry& at(std::string_view key) const {
    if (const Entry* e = find(key))
      return *e;
    throw std::out_of_range(unknownKey(key));
  }
  /// every key, in panel order
  std::vector<std::string> keys() const {
    std::vector<std::string> out;
    for (const Entry& e : m_entries)
      out.push_back(e.key);
    return out;
  }
  /// what one entry is called in messages: "parameter", "render setting"
  const std::string& noun() const { return m_noun; }
  /// "unknown parameter 'kye' (did you mean key?)"
  std::string unknownKey(std::string_view key) const {
    return "unknown " + m_noun + " '" + std::string(key) + "'" + didYouMean(key, keys());
  }

  /// Sets every parameter of `s` to its default.
  void applyDefaults(S& s) const {
    for (const Entry& e : m_entries) {
      visit(e, s, [&](auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, Choice>)
          v.index = std::get<Choice>(e.defaultValue).index;
        else
          v = std::get<T>(e.defaultValue);
      });
    }
  }
  /// Checks the relations between parameters (e.g. dt_min <= dt_max); "" or the one-line error.
  std::string validate(const S& s) const { return m_validate ? m_validate(s) : std::string(); }

  /// value of a scalar parameter (Number, Integer, Boolean, Seed; Choice: its index) as double; 0 for Vector3
  static double getScalar(const S& s, const Entry& e) {
    return visit(e, s, [](const auto& v) -> double {
      using T = std::decay_t<decltype(v)>;
      if constexpr (std::is_same_v<T, std::array<double, 3>>)
        return 0.0;
      else if constexpr (std::is_same_v<T, Choice>)
        return double(v.index);
      else
        return double(v);
    });
  }
  /// value of a Vector3 parameter; zeros for the other kinds
  static std::array<double, 3> getVec3(const S& s, const Entry& e) {
    return visit(e, s, [](const auto& v) -> std::array<double, 3> {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::array<double, 3>>)
        return v;
      else
        return {0.0, 0.0, 0.0};
    });
  }
  /// Sets a scalar parameter (Boolean: 0 or 1, Choice: the index); "" or why not (out of range, not integral,
  /// a 3-vector). Leaves `s` unchanged on error.
  static std::string setScalar(S& s, const Entry& e, double value) {
    if (e.kind == ParamKind::Vector3)
      return e.key + " is a 3-vector";
    std::string error = param_detail::checkScalar(e.key, e.kind, e.min, e.max, value);
    if (!error.empty())
      return error;
    visit(e, s, [&](auto& v) {
      using T = std::decay_t<decltype(v)>;
      if constexpr (std::is_same_v<T, Choice>)
        v.index = int(value);
      else if constexpr (std::is_same_v<T, bool>)
        v = value != 0.0;
      else if constexpr (!std::is_same_v<T, std::array<double, 3>>)
        v = static_cast<T>(value);
    });
    return {};
  }
  /// Sets a Vector3 parameter; "" or why not (a component out of range, not a 3-vector).
  static std::string setVec3(S& s, const Entry& e, const std::array<double, 3>& value) {
    if (e.kind != ParamKind::Vector3)
      return e.key + " is not a 3-vector";
    for (double c : value) {
      if (!std::isfinite(c) || c < e.min || c > e.max)
        return e.key + " has a component out of range [" + formatNumber(e.min) + ", " + formatNumber(e.max) +
               "]";
    }
    visit(e, s, [&](auto& v) {
      if constexpr (std::is_same_v<std::decay_t<decltype(v)>, std::array<double, 3>>)
        v = value;
    });
    return {};
  }
  /// Sets a Choice parameter by name; "" or the error naming the choices.
  static std::string setChoice(S& s, const Entry& e, std::string_view name) {
    if (e.kind != ParamKind::Choice)
      return e.key + " is not a choice";
    int index = 0;
    std::string error = param_detail::parseChoice(e.key, e.choices, name, index);
    return error.empty() ? setScalar(s, e, double(index)) : error;
  }
  /// Sets a parameter from its text form (numbers, true/false, "x,y,z", a choice's name); "" or the error.
  static std::string setText(S& s, const Entry& e, std::string_view text) {
    if (e.kind == ParamKind::Vector3) {
      std::array<double, 3> v{};
      std::string error = param_detail::parseVec3(e.key, text, v);
      return error.empty() ? setVec3(s, e, v) : error;
    }
    if (e.kind == ParamKind::Choice)
      return setChoice(s, e, text);
    double v = 0.0;
    std::string error = param_detail::parseScalar(e.key, e.kind, text, v);
    return error.empty() ? setScalar(s, e, v) : error;
  }
  /// The text form of a parameter's value, which setText reads back to the same value.
  static std::string text(const S& s, const Entry& e) {
    return visit(e, s, [](const auto& v) -> std::string {
      using T = std::decay_t<decltype(v)>;
      if constexpr (std::is_same_v<T, std::array<double, 3>>) {
        return param_detail::formatValue(v[0]) + "," + param_detail::formatValue(v[1]) + "," +
               param_detail::formatValue(v[2]);
      } else if constexpr (std::is_same_v<T, Choice>) {
        return v.name();
      } else if constexpr (std::is_same_v<T, bool>) {
        return v ? "true" : "false";
      } else if constexpr (std::is_same_v<T, std::uint64_t> || std::is_same_v<T, int>) {
        return std::to_string(v);
      } else {
        return param_detail::formatValue(double(v));
      }
    });
  }
  /// whether the parameter has the same value in `a` and `b`
  static bool equal(const Entry& e, const S& a, const S& b) {
    // named templates rather than nested generic lambdas: clang 14 (the fuzz build) rejects the latter
    return visit(
        e, a, [&](const auto& va) { return visit(e, b, [&](const auto& vb) { return sameValue(va, vb); }); });
  }
  /// Copies the parameter's value from `from` into `to`, unchecked (both hold valid values).
  static void copy(const Entry& e, const S& from, S& to) {
    visit(e, from, [&](const auto& src) { visit(e, to, [&](auto& dst) { copyValue(src, dst); }); });
  }
  template <class A, class B>
  static bool sameValue(const A& va, const B& vb) {
    if constexpr (std::is_same_v<A, Choice> && std::is_same_v<B, Choice>)
      return va.index == vb.index;
    else if constexpr (std::is_same_v<A, B>)
      return va == vb;
    else
      return false;
  }
  template <class A, class B>
  static void copyValue(const A& src, B& dst) {
    if constexpr (std::is_same_v<A, Choice> && std::is_same_v<B, Choice>)
      dst.index = src.index;
    else if constexpr (std::is_same_v<A, B>)
      dst = src;
  }
  /// whether every parameter of the table has the same value in `a` and `b`
  bool allEqual(const S& a, const S& b) const {
    for (const Entry& e : m_entries) {
      if (!equal(e, a, b))
        return false;
    }
    return true;
  }

  /// Applies one "KEY=VALUE" (VALUE as setText reads it). Returns "" or a one-line error: "expected
  /// KEY=VALUE, got 'x'", "unknown parameter 'kye' (did you mean key?)", a type or a range error. Relations
  /// between parameters are not checked here: call validate() after the last assignment (or use assignAll).
  std::string assign(S& s, std::string_view keyValue) const {
    const std::size_t eq = keyValue.find('=');
    if (eq == std::string_view::npos || eq == 0)
      return "expected KEY=VALUE, got '" + std::string(keyValue) + "'";
    const Entry* e = find(keyValue.substr(0, eq));
    if (!e)
      return unknownKey(keyValue.substr(0, eq));
    return setText(s, *e, keyValue.substr(eq + 1));
  }
  /// Applies every "KEY=VALUE" in order, then checks the relations; "" or the first error. `s` may be partly
  /// changed on error.
  std::string assignAll(S& s, const std::vector<std::string>& keyValues) const {
    for (const std::string& kv : keyValues) {
      std::string error = assign(s, kv);
      if (!error.empty())
        return error;
    }
    return validate(s);
  }

  /// One help line per entry: "key=VALUE  description [unit], range [min, max], default d".
  std::vector<std::string> helpLines() const {
    std::vector<std::string> out;
    for (const Entry& e : m_entries) {
      std::string range;
      switch (e.kind) {
        case ParamKind::Boolean:
          range = "true or false";
          break;
        case ParamKind::Choice:
          range = joinNames(e.choices);
          break;
        case ParamKind::Vector3:
          range = "x,y,z each in [" + formatNumber(e.min) + ", " + formatNumber(e.max) + "]";
          break;
        default:
          range = "[" + formatNumber(e.min) + ", " + formatNumber(e.max) + "]";
      }
      out.push_back(e.key + ": " + e.description + " [" + e.unit + "], " + range + ", default " +
                    defaultText(e));
    }
    return out;
  }
  /// the text form of the entry's default
  static std::string defaultText(const Entry& e) {
    return std::visit(
        [&](const auto& v) -> std::string {
          using T = std::decay_t<decltype(v)>;
          if constexpr (std::is_same_v<T, std::array<double, 3>>)
            return param_detail::formatValue(v[0]) + "," + param_detail::formatValue(v[1]) + "," +
                   param_detail::formatValue(v[2]);
          else if constexpr (std::is_same_v<T, Choice>)
            return e.choices[std::size_t(v.index)];
          else if constexpr (std::is_same_v<T, bool>)
            return v ? "true" : "false";
          else if constexpr (std::is_same_v<T, std::uint64_t> || std::is_same_v<T, int>)
            return std::to_string(v);
          else
            return param_detail::formatValue(double(v));
        },
        e.defaultValue);
  }

 protected:
  /// `noun` names an entry in messages; `relations` checks the relations between parameters (may be null)
  explicit ParamTableOf(std::string noun, std::string (*relations)(const S&) = nullptr)
      : m_noun(std::move(noun)), m_validate(relations) {}

  /// Declares a parameter held by `member` (double, float, int, bool, std::uint64_t or std::array<double, 3>)
  /// with its default; the kind follows from the member's type. Booleans range over [0, 1].
  template <class T, class D>
  void add(std::string key, std::string group, std::string unit, double min, double max, bool live,
           std::string description, T S::*member, D defaultValue) {
    ParamKind kind = ParamKind::Number;
    if constexpr (std::is_same_v<T, int>)
      kind = ParamKind::Integer;
    else if constexpr (std::is_same_v<T, bool>)
      kind = ParamKind::Boolean;
    else if constexpr (std::is_same_v<T, std::uint64_t>)
      kind = ParamKind::Seed;
    else if constexpr (std::is_same_v<T, std::array<double, 3>>)
      kind = ParamKind::Vector3;
    else
      static_assert(std::is_floating_point_v<T>, "unsupported parameter type");
    m_entries.push_back(Entry{std::move(key),
                              std::move(group),
                              std::move(unit),
                              kind,
                              min,
                              max,
                              std::move(description),
                              live,
                              member,
                              ParamValue(T(defaultValue)),
                              {}});
  }
  /// Declares an enum parameter held by the member M, its values named by `names` in enum order (0, 1, ...).
  template <auto M>
  void addChoice(std::string key, std::string group, std::string description, bool live,
                 std::vector<std::string> names, int defaultIndex) {
    using E = std::decay_t<decltype(std::declval<S&>().*M)>;
    static_assert(std::is_enum_v<E>, "addChoice needs an enum member");
    ChoiceMember<S> member{[](const S& s) { return int(s.*M); }, [](S& s, int i) { s.*M = E(i); }};
    const double max = double(names.size()) - 1.0;
    m_entries.push_back(Entry{std::move(key), std::move(group), "-", ParamKind::Choice, 0.0, max,
                              std::move(description), live, member, ParamValue(Choice{defaultIndex, nullptr}),
                              std::move(names)});
  }

 private:
  std::vector<Entry> m_entries;
  std::string m_noun;
  std::string (*m_validate)(const S&) = nullptr;
};

}  // namespace fp::sim

// The settings of an Options struct, each defined once (the Ceres pattern): one Schema entry
// holds a setting's JSON name, command-line flag, help, valid range and where it lives in the
// struct; its default is the struct member's initializer. FromJson (JSON-pointer errors), ToJson,
// Validate and the command-line bindings (experiments/cli/bind.h) all read the same entries, so a
// default, a range or a name cannot disagree between `quijibo run`, a subcommand and Python.
// Below the libraries (optim, mesh, monopole, the pipeline), so that each can describe its own
// Options; a range two structs share is a ValueRange constant beside the concept it bounds.
#pragma once

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "util/error.h"
#include "util/json_reader.h"

namespace quijibo {

// kNumbers: a list of numbers, each in the range, of one of the lengths in `sizes`.
enum class SettingType { kInteger, kNumber, kBoolean, kString, kChoice, kPath, kNumbers };

// A numeric setting's valid range: [lo, hi], either end open or infinite.
struct ValueRange {
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool open_lo = false, open_hi = false;
};

// One setting of an Options struct O. A key "a/b" is the member b of the object a
// ("max_iterations/V").
template <class O>
struct Setting {
  std::string key;   // JSON name within the Options' object
  std::string flag;  // CLI11 names ("-r,--resolution"); empty: not a command-line option.
                     // A boolean whose flag starts with "--no-" sets false, else true.
  std::string help;
  std::string doc;  // the meaning in docs/experiments.md's table when more than `help` says
  SettingType type = SettingType::kNumber;
  double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
  bool open_lo = false, open_hi = false;  // (lo, ...  and  ..., hi)
  std::vector<std::string> choices;       // kChoice
  bool must_exist = true;                 // kPath: a readable file
  std::vector<int> sizes;                 // kNumbers: the allowed lengths
  // Optional settings (std::optional members) are written only when set; unset, the library's
  // default applies.
  bool optional = false;
  std::function<nlohmann::json(const O&)> get;  // null: an unset optional
  std::function<void(O&, const nlohmann::json&)> set;
  std::function<bool(const O&)> applies;  // empty: always
  // Optional settings: the value that applies when unset (the library's default), for --help.
  std::function<nlohmann::json(const O&)> fallback;

  bool Applies(const O& o) const { return !applies || applies(o); }
};

// "[8, 1024]", "(0, 100]", "a number >= 0", ...: the range as messages and --help show it.
std::string DescribeRange(SettingType type, double lo, double hi, bool open_lo, bool open_hi = false);
// "integer", "number", "boolean", "string", "choice", "path", "numbers".
std::string SettingTypeName(SettingType type);
// A setting as `quijibo settings` prints it (docs/experiments.md's tables and the tests that keep
// the faces in agreement read it): key, flag, help, type, default (null: none), and when they
// apply range (as messages write it), lo/hi/open_lo/open_hi (finite ends only), choices, sizes
// (Schema::Describe adds doc).
nlohmann::json DescribeSetting(const std::string& key, const std::string& flag, const std::string& help,
                               SettingType type, const nlohmann::json& default_value, double lo, double hi,
                               bool open_lo, bool open_hi, const std::vector<std::string>& choices,
                               const std::vector<int>& sizes);
// For a library's Validate(): "" or "<name>: expected an integer in [8, 1024], found 0".
std::string CheckRange(const std::string& name, SettingType type, double value, const ValueRange& range);
// What is wrong with `value` for a setting of this type, range and choices; empty when valid.
std::string CheckValue(const nlohmann::json& value, SettingType type, double lo, double hi, bool open_lo, bool open_hi,
                       const std::vector<std::string>& choices, const std::vector<int>& sizes);
// Reads the value at `pointer` with the type's JSON checks (an integer may be written 97.0), the
// range and the choices; a kPath resolves against `base` (and must exist when asked). Errors go
// through r.fail (file and JSON pointer).
nlohmann::json ReadValue(const JsonReader& r, const std::string& pointer, SettingType type, double lo, double hi,
                         bool open_lo, bool open_hi, const std::vector<std::string>& choices,
                         const std::vector<int>& sizes, const std::filesystem::path& base, bool must_exist);
// `p` relative to `base` (absolute and normalized), or `p` when absolute.
std::string ResolvePath(const std::filesystem::path& base, const std::string& p);

// An enum's names, defined once beside the enum: Parse (with the names messages list), Name, and
// the choices a setting offers (names()). Aliases are accepted by Parse but not listed.
//   inline const EnumNames<FrameScale> kFrameScales("frame scale", {{FrameScale::kTrap, "trap"}, ...});
template <class E>
class EnumNames {
 public:
  EnumNames(std::string what, std::vector<std::pair<E, std::string>> entries,
            std::vector<std::pair<E, std::string>> aliases = {})
      : what_(std::move(what)), entries_(std::move(entries)), aliases_(std::move(aliases)) {
    for (const auto& e : entries_) names_.push_back(e.second);
  }
  // Throws quijibo::Error: unknown <what> "x" (expected a, b or c).
  E Parse(const std::string& name) const {
    for (const auto* list : {&entries_, &aliases_})
      for (const auto& [value, n] : *list)
        if (n == name) return value;
    std::string expected;
    for (std::size_t k = 0; k < names_.size(); ++k)
      expected += (k == 0 ? "" : k + 1 == names_.size() ? " or " : ", ") + names_[k];
    throw Error("unknown " + what_ + " \"" + name + "\" (expected " + expected + ")");
  }
  const std::string& Name(E value) const {
    for (const auto& e : entries_)
      if (e.first == value) return e.second;
    throw Error("unnamed " + what_);  // a value outside the enum's table: a programming error
  }
  const std::vector<std::string>& names() const { return names_; }

 private:
  std::string what_;
  std::vector<std::pair<E, std::string>> entries_, aliases_;
  std::vector<std::string> names_;
};

namespace detail {
template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {
  using type = T;
};
// The member a reference accessor points at, and whether it is a std::optional.
template <class O, class Ref>
using Member = std::remove_reference_t<std::invoke_result_t<Ref, O&>>;
}  // namespace detail

template <class O>
class Schema {
 public:
  // `ref` is a callable O& -> T& naming the member: [](auto& o) -> int& { return o.meshing.resolution; }.
  // A std::optional<T> member makes the setting optional.
  template <class Ref>
  Schema& Integer(std::string key, std::string flag, std::string help, Ref ref, long long lo, long long hi) {
    return Add(Typed(std::move(key), std::move(flag), std::move(help), SettingType::kInteger, ref, double(lo),
                     double(hi), false));
  }
  template <class Ref>
  Schema& Number(std::string key, std::string flag, std::string help, Ref ref, double lo, double hi,
                 bool open_lo = false) {
    return Add(Typed(std::move(key), std::move(flag), std::move(help), SettingType::kNumber, ref, lo, hi, open_lo));
  }
  template <class Ref>
  Schema& Integer(std::string key, std::string flag, std::string help, Ref ref, const ValueRange& r) {
    return Add(Ranged(std::move(key), std::move(flag), std::move(help), SettingType::kInteger, ref, r));
  }
  template <class Ref>
  Schema& Number(std::string key, std::string flag, std::string help, Ref ref, const ValueRange& r) {
    return Add(Ranged(std::move(key), std::move(flag), std::move(help), SettingType::kNumber, ref, r));
  }
  template <class Ref>
  Schema& Boolean(std::string key, std::string flag, std::string help, Ref ref) {
    return Add(Typed(std::move(key), std::move(flag), std::move(help), SettingType::kBoolean, ref, 0, 0, false));
  }
  template <class Ref>
  Schema& String(std::string key, std::string flag, std::string help, Ref ref) {
    return Add(Typed(std::move(key), std::move(flag), std::move(help), SettingType::kString, ref, 0, 0, false));
  }
  template <class Ref>
  Schema& Choice(std::string key, std::string flag, std::string help, Ref ref, std::vector<std::string> choices) {
    Setting<O> s = Typed(std::move(key), std::move(flag), std::move(help), SettingType::kChoice, ref, 0, 0, false);
    s.choices = std::move(choices);
    return Add(std::move(s));
  }
  // A setting held in another form (an enum): `get` gives its name, `set` parses one.
  Schema& Enum(std::string key, std::string flag, std::string help, std::vector<std::string> choices,
               std::function<std::string(const O&)> get, std::function<void(O&, const std::string&)> set) {
    Setting<O> s;
    s.key = std::move(key), s.flag = std::move(flag), s.help = std::move(help);
    s.type = SettingType::kChoice;
    s.choices = std::move(choices);
    s.get = [get](const O& o) { return nlohmann::json(get(o)); };
    s.set = [set](O& o, const nlohmann::json& v) { set(o, v.get<std::string>()); };
    return Add(std::move(s));
  }
  // A boolean held in another form: `get` and `set` convert.
  Schema& BooleanOf(std::string key, std::string flag, std::string help, std::function<bool(const O&)> get,
                    std::function<void(O&, bool)> set) {
    Setting<O> s;
    s.key = std::move(key), s.flag = std::move(flag), s.help = std::move(help);
    s.type = SettingType::kBoolean;
    s.get = [get](const O& o) { return nlohmann::json(get(o)); };
    s.set = [set](O& o, const nlohmann::json& v) { set(o, v.get<bool>()); };
    return Add(std::move(s));
  }
  // A list of numbers, each in [lo, hi], of one of the lengths `sizes`.
  template <class Ref>
  Schema& Numbers(std::string key, std::string flag, std::string help, Ref ref, std::vector<int> sizes, double lo,
                  double hi) {
    Setting<O> s = Typed(std::move(key), std::move(flag), std::move(help), SettingType::kNumbers, ref, lo, hi, false);
    s.sizes = std::move(sizes);
    return Add(std::move(s));
  }
  template <class Ref>
  Schema& Path(std::string key, std::string flag, std::string help, Ref ref, bool must_exist = true) {
    Setting<O> s = Typed(std::move(key), std::move(flag), std::move(help), SettingType::kPath, ref, 0, 0, false);
    s.must_exist = must_exist;
    return Add(std::move(s));
  }
  // The last (optional) setting's value when unset, as --help shows it.
  template <class F>
  Schema& Fallback(F f) {
    settings_.back().fallback = [f](const O& o) { return nlohmann::json(f(o)); };
    return *this;
  }
  // The last setting's range excludes its upper bound.
  Schema& OpenAbove() {
    settings_.back().open_hi = true;
    return *this;
  }
  // The last setting's meaning in docs/experiments.md (Markdown), when more than its help.
  Schema& Doc(std::string doc) {
    settings_.back().doc = std::move(doc);
    return *this;
  }
  // The last setting applies only when `applies(options)` (e.g. to one kind of initial guess).
  Schema& When(std::function<bool(const O&)> applies) {
    settings_.back().applies = std::move(applies);
    return *this;
  }

  // Settings several Options structs share, each defined once beside its concept: `add` is a
  // callable (Schema<O>&) that adds them, with the same key, flag, help, range and doc in every
  // struct that holds them (optim::PrecisionSetting, ...).
  template <class F>
  Schema& With(F&& add) {
    std::forward<F>(add)(*this);
    return *this;
  }

  const std::vector<Setting<O>>& settings() const { return settings_; }
  // The setting of `key` that applies to `o` (several may share a key under different kinds).
  const Setting<O>* Find(const std::string& key, const O& o) const {
    for (const auto& s : settings_)
      if (s.key == key && s.Applies(o)) return &s;
    return nullptr;
  }

  // Reads the settings present at `pointer` into `o` (missing keys keep o's values); settings are
  // read in order, so a later one's `applies` sees the earlier ones (a kind first). Unknown keys
  // are errors, except `extra_keys`, which the caller reads.
  void Read(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base, O& o,
            const std::vector<std::string>& extra_keys = {}) const {
    if (!r.has(pointer)) return;
    if (!r.at(pointer).is_object()) r.fail(pointer, "expected an object, found " + JsonReader::describe(r.at(pointer)));
    std::vector<std::string> keys = extra_keys;
    std::vector<std::pair<std::string, std::vector<std::string>>> objects;  // "a/b": b among a's keys
    for (const auto& s : settings_) {
      if (!s.Applies(o)) continue;
      const std::size_t slash = s.key.find('/');
      const std::string top = s.key.substr(0, slash);
      if (std::find(keys.begin(), keys.end(), top) == keys.end()) keys.push_back(top);
      if (slash != std::string::npos) {
        auto it = std::find_if(objects.begin(), objects.end(), [&](const auto& e) { return e.first == top; });
        if (it == objects.end()) {
          const std::string p = pointer + "/" + top;
          if (r.has(p) && !r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
          objects.emplace_back(top, std::vector<std::string>());
          it = objects.end() - 1;
        }
        it->second.push_back(s.key.substr(slash + 1));
      }
      const std::string p = pointer + "/" + s.key;
      if (r.has(p))
        s.set(o, ReadValue(r, p, s.type, s.lo, s.hi, s.open_lo, s.open_hi, s.choices, s.sizes, base, s.must_exist));
    }
    for (const auto& [top, members] : objects)
      if (r.has(pointer + "/" + top)) r.allow_keys(pointer + "/" + top, members);
    r.allow_keys(pointer, keys);
  }
  // An Options struct as its JSON object says (missing keys keep `start`'s values), and back: the
  // FromJson and ToJson of a struct that has nothing but its settings.
  O FromJson(const JsonReader& r, const std::string& pointer, const std::filesystem::path& base, O start = O()) const {
    Read(r, pointer, base, start);
    return start;
  }
  nlohmann::json ToJson(const O& o) const {
    nlohmann::json j = nlohmann::json::object();
    Write(o, j);
    return j;
  }
  // Every setting (DescribeSetting), with its default in `defaults`.
  nlohmann::json Describe(const O& defaults = O()) const {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& s : settings_) {
      nlohmann::json def = s.get(defaults);
      if (def.is_null() && s.fallback) def = s.fallback(defaults);
      out.push_back(DescribeSetting(s.key, s.flag, s.help, s.type, def, s.lo, s.hi, s.open_lo, s.open_hi, s.choices,
                                    s.sizes));
      if (!s.doc.empty()) out.back()["doc"] = s.doc;
    }
    return out;
  }
  // Every setting that applies (unset optionals left out) into `out`.
  void Write(const O& o, nlohmann::json& out) const {
    if (!out.is_object()) out = nlohmann::json::object();
    for (const auto& s : settings_) {
      if (!s.Applies(o)) continue;
      nlohmann::json v = s.get(o);
      if (!v.is_null()) out[nlohmann::json::json_pointer("/" + s.key)] = std::move(v);
    }
  }
  // The settings that apply and differ from `defaults`'s into `out`: what a user changed, as an
  // experiment written by a command (`bench shapes`) states it.
  void WriteChanged(const O& o, nlohmann::json& out, const O& defaults = O()) const {
    if (!out.is_object()) out = nlohmann::json::object();
    for (const auto& s : settings_) {
      if (!s.Applies(o)) continue;
      nlohmann::json v = s.get(o);
      if (!v.is_null() && v != s.get(defaults)) out[nlohmann::json::json_pointer("/" + s.key)] = std::move(v);
    }
  }
  // The first setting outside its range, as "<key>: expected ..., found ...", or empty (a key
  // "a/b" as "a.b").
  std::string Check(const O& o) const {
    for (const auto& s : settings_) {
      if (!s.Applies(o)) continue;
      const nlohmann::json v = s.get(o);
      if (v.is_null()) continue;
      if (std::string why = CheckValue(v, s.type, s.lo, s.hi, s.open_lo, s.open_hi, s.choices, s.sizes); !why.empty())
        return DottedKey(s.key) + ": " + why;
    }
    return {};
  }

 private:
  static std::string DottedKey(std::string key) {
    std::replace(key.begin(), key.end(), '/', '.');
    return key;
  }
  Schema& Add(Setting<O> s) {
    settings_.push_back(std::move(s));
    return *this;
  }
  template <class Ref>
  static Setting<O> Typed(std::string key, std::string flag, std::string help, SettingType type, Ref ref, double lo,
                          double hi, bool open_lo) {
    using M = detail::Member<O, Ref>;
    Setting<O> s;
    s.key = std::move(key), s.flag = std::move(flag), s.help = std::move(help);
    s.type = type, s.lo = lo, s.hi = hi, s.open_lo = open_lo;
    if constexpr (detail::IsOptional<M>::value) {
      using T = typename detail::IsOptional<M>::type;
      s.optional = true;
      s.get = [ref](const O& o) -> nlohmann::json {
        const auto& m = ref(const_cast<O&>(o));
        return m ? ToJsonValue<T>(*m) : nlohmann::json(nullptr);
      };
      s.set = [ref](O& o, const nlohmann::json& v) { ref(o) = FromJsonValue<T>(v); };
    } else {
      s.get = [ref](const O& o) -> nlohmann::json { return ToJsonValue<M>(ref(const_cast<O&>(o))); };
      s.set = [ref](O& o, const nlohmann::json& v) { ref(o) = FromJsonValue<M>(v); };
    }
    return s;
  }
  // A setting whose range is a shared ValueRange (both ends' openness from it).
  template <class Ref>
  static Setting<O> Ranged(std::string key, std::string flag, std::string help, SettingType type, Ref ref,
                           const ValueRange& r) {
    Setting<O> s = Typed(std::move(key), std::move(flag), std::move(help), type, ref, r.lo, r.hi, r.open_lo);
    s.open_hi = r.open_hi;
    return s;
  }
  // Integers are written as JSON integers, numbers as JSON numbers with a fraction (97 vs 97.0 in
  // the resolved experiment and in the stage hashes), as the experiments have always been resolved.
  template <class T>
  static nlohmann::json ToJsonValue(const T& v) {
    if constexpr (std::is_same_v<T, bool>)
      return v;
    else if constexpr (std::is_integral_v<T>)
      return static_cast<long long>(v);
    else if constexpr (std::is_floating_point_v<T>)
      return static_cast<double>(v);
    else if constexpr (std::is_same_v<T, std::vector<double>>) {
      nlohmann::json a = nlohmann::json::array();
      for (double x : v) a.push_back(x);
      return a;
    } else
      return nlohmann::json(v);
  }
  template <class T>
  static T FromJsonValue(const nlohmann::json& v) {
    if constexpr (std::is_same_v<T, bool>)
      return v.get<bool>();
    else if constexpr (std::is_integral_v<T>)
      return static_cast<T>(v.get<long long>());
    else if constexpr (std::is_floating_point_v<T>)
      return static_cast<T>(v.get<double>());
    else
      return v.get<T>();
  }

  std::vector<Setting<O>> settings_;
};

}  // namespace quijibo

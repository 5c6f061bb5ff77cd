// The small arithmetic language of scene parameters (scene_parameters.hpp):
// numbers, names, + - * /, unary signs and parentheses, by recursive
// descent.
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "dynamics/scene_parameters.hpp"

namespace msfab {

namespace {

struct Token {
  enum Kind { kNumber, kName, kOperator, kEnd } kind = kEnd;
  std::string text;
  double value = 0;
  std::size_t position = 0;
};

bool name_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }
bool digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

// Splits `text` into tokens; false (with `why`) on a character or number
// the language does not have.
bool tokenize(const std::string& text, std::vector<Token>& out, std::string& why) {
  std::size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    if (c == ' ' || c == '\t') {
      ++i;
    } else if (name_start(c)) {
      std::size_t j = i;
      while (j < text.size() && name_char(text[j])) ++j;
      out.push_back({Token::kName, text.substr(i, j - i), 0, i});
      i = j;
    } else if (digit(c) || (c == '.' && i + 1 < text.size() && digit(text[i + 1]))) {
      // strtod would also take "inf", hex and signs; scan the decimal form ourselves.
      std::size_t j = i;
      while (j < text.size() && digit(text[j])) ++j;
      if (j < text.size() && text[j] == '.') ++j;
      while (j < text.size() && digit(text[j])) ++j;
      if (j < text.size() && (text[j] == 'e' || text[j] == 'E')) {
        std::size_t k = j + 1;
        if (k < text.size() && (text[k] == '+' || text[k] == '-')) ++k;
        if (k >= text.size() || !digit(text[k])) {
          why = "malformed number at position " + std::to_string(i + 1);
          return false;
        }
        while (k < text.size() && digit(text[k])) ++k;
        j = k;
      }
      if (j < text.size() && (name_char(text[j]) || text[j] == '.')) {
        why = "malformed number at position " + std::to_string(i + 1);
        return false;
      }
      out.push_back({Token::kNumber, text.substr(i, j - i), std::strtod(text.substr(i, j - i).c_str(), nullptr), i});
      i = j;
    } else if (c == '+' || c == '-' || c == '*' || c == '/' || c == '(' || c == ')') {
      out.push_back({Token::kOperator, std::string(1, c), 0, i});
      ++i;
    } else {
      why = std::string("unexpected character '") + c + "' at position " + std::to_string(i + 1);
      return false;
    }
  }
  out.push_back({Token::kEnd, "", 0, text.size()});
  return true;
}

class Parser {
 public:
  Parser(const std::vector<Token>& tokens, const ParameterValues& values) : t_(tokens), values_(values) {}

  double parse() {
    const double v = sum();
    if (t_[i_].kind != Token::kEnd) fail("unexpected '" + t_[i_].text + "'");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    throw std::invalid_argument(what + " at position " + std::to_string(t_[i_].position + 1));
  }
  bool is(const char* op) const { return t_[i_].kind == Token::kOperator && t_[i_].text == op; }

  double sum() {
    double v = product();
    while (is("+") || is("-")) {
      const bool plus = is("+");
      ++i_;
      const double r = product();
      v = plus ? v + r : v - r;
    }
    return v;
  }
  double product() {
    double v = unary();
    while (is("*") || is("/")) {
      const bool times = is("*");
      ++i_;
      const std::size_t at = i_;
      const double r = unary();
      if (!times && r == 0) {
        i_ = at;
        fail("division by zero");
      }
      v = times ? v * r : v / r;
    }
    return v;
  }
  double unary() {
    if (is("-")) return ++i_, -unary();
    if (is("+")) return ++i_, unary();
    return primary();
  }
  double primary() {
    const Token& tok = t_[i_];
    if (tok.kind == Token::kNumber) return ++i_, tok.value;
    if (tok.kind == Token::kName) {
      const auto it = values_.find(tok.text);
      if (it == values_.end()) {
        std::string known;
        for (const auto& [name, value] : values_) known += (known.empty() ? "" : ", ") + name;
        fail("unknown parameter '" + tok.text + "' (defined: " + (known.empty() ? "none" : known) + ")");
      }
      return ++i_, it->second;
    }
    if (is("(")) {
      ++i_;
      const double v = sum();
      if (!is(")")) fail("missing ')'");
      ++i_;
      return v;
    }
    fail(tok.kind == Token::kEnd ? "expression ends early" : "unexpected '" + tok.text + "'");
  }

  const std::vector<Token>& t_;
  const ParameterValues& values_;
  std::size_t i_ = 0;
};

}  // namespace

double evaluate_parameter_expression(const std::string& text, const ParameterValues& values) {
  std::vector<Token> tokens;
  std::string why;
  if (!tokenize(text, tokens, why)) throw std::invalid_argument(why);
  const double v = Parser(tokens, values).parse();
  if (!std::isfinite(v)) throw std::invalid_argument("the value is not finite");
  return v;
}

bool looks_like_expression(const std::string& text, const ParameterValues& values) {
  std::vector<Token> tokens;
  std::string why;
  if (!tokenize(text, tokens, why)) return false;
  bool operator_seen = false, number_seen = false;
  for (const Token& t : tokens) {
    if (t.kind == Token::kName && values.count(t.text)) return true;
    operator_seen |= t.kind == Token::kOperator;
    number_seen |= t.kind == Token::kNumber;
  }
  // Names joined by '-' or '/' ("block-drop", "out/run") are words and paths.
  return operator_seen && number_seen;
}

}  // namespace msfab

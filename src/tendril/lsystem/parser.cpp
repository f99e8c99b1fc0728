#include "tendril/lsystem/parser.h"

#include "tendril/core/error.h"
#include "tendril/core/json_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <cstring>

namespace tendril::lsystem {

namespace {

using syntax::Assignment;
using syntax::Expr;
using syntax::ExprPtr;
using syntax::LeafShapeDecl;
using syntax::Module;
using syntax::ModuleDecl;
using syntax::ModuleString;
using syntax::Setting;
using syntax::Stmt;
using syntax::SurfaceDecl;

// Nesting of expressions, blocks and parameter lists; deeper input is an error rather than a
// stack overflow.
constexpr int kMaxNesting = 200;

enum class Directive {
  LSystem, Seed, DerivationLength, MaxLength, Define, Global, Module, Ignore, Consider, Axiom, Angle, Step,
  Width, WidthFactor, Tropism, Elasticity, LeafThickness, LeafShapes, Colors, Bark, Surface, Start, StartEach,
  EndEach, End, Production, Decomposition, Interpretation, MaximumDepth,
};

struct DirectiveName {
  const char* text;
  Directive d;
};

const DirectiveName kDirectives[] = {
    {"lsystem", Directive::LSystem},
    {"seed", Directive::Seed},
    {"derivation length", Directive::DerivationLength},
    {"max length", Directive::MaxLength},
    {"define", Directive::Define},
    {"global", Directive::Global},
    {"globals", Directive::Global},
    {"module", Directive::Module},
    {"modules", Directive::Module},
    {"ignore", Directive::Ignore},
    {"consider", Directive::Consider},
    {"axiom", Directive::Axiom},
    {"angle", Directive::Angle},
    {"step", Directive::Step},
    {"width", Directive::Width},
    {"width factor", Directive::WidthFactor},
    {"tropism", Directive::Tropism},
    {"elasticity", Directive::Elasticity},
    {"leaf thickness", Directive::LeafThickness},
    {"leaf shapes", Directive::LeafShapes},
    {"colors", Directive::Colors},
    {"colours", Directive::Colors},
    {"bark", Directive::Bark},
    {"surface", Directive::Surface},
    {"start", Directive::Start},
    {"starteach", Directive::StartEach},
    {"start each", Directive::StartEach},
    {"endeach", Directive::EndEach},
    {"end each", Directive::EndEach},
    {"end", Directive::End},
    {"production", Directive::Production},
    {"productions", Directive::Production},
    {"decomposition", Directive::Decomposition},
    {"interpretation", Directive::Interpretation},
    {"homomorphism", Directive::Interpretation},
    {"maximum depth", Directive::MaximumDepth},
};

bool isIdentStart(int c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_'; }
bool isIdentChar(int c) { return isIdentStart(c) || (c >= '0' && c <= '9'); }
bool isDigit(int c) { return c >= '0' && c <= '9'; }
bool isTurtleSymbol(int c) { return c > 0 && std::strchr("+-&^\\/|[]!'$.{}%", c) != nullptr; }

std::string describeChar(int c) {
  if (c < 0) return "the end of the file";
  if (c == '\n') return "the end of the line";
  if (c >= 32 && c < 127) return fmt::format("'{}'", char(c));
  return fmt::format("byte 0x{:02x}", unsigned(c));
}

class Parser {
 public:
  Parser(std::string_view text, std::string source) : t_(text), source_(std::move(source)) {
    lineStarts_.push_back(0);
    for (size_t i = 0; i < t_.size(); ++i)
      if (t_[i] == '\n') lineStarts_.push_back(i + 1);
  }

  syntax::Grammar parse() {
    for (;;) {
      skipBlank(true);
      if (eof()) break;
      if (lineStartsWith("#define")) {
        parseHashDefine();
        continue;
      }
      if (peek() == '#') {
        // A preprocessor line other than #define (comments were skipped by skipBlank).
        error(p_, "only #define is supported among cpfg's preprocessor lines");
      }
      if (tryEndLSystem()) break;
      if (tryDirective()) continue;
      parseProduction();
    }
    return std::move(g_);
  }

 private:
  // --- characters and positions -------------------------------------------------------

  bool eof() const { return p_ >= t_.size(); }
  int peek(size_t k = 0) const { return p_ + k < t_.size() ? static_cast<unsigned char>(t_[p_ + k]) : -1; }
  SourcePos posAt(size_t offset) const {
    size_t line = std::upper_bound(lineStarts_.begin(), lineStarts_.end(), offset) - lineStarts_.begin();
    return {uint32_t(line), uint32_t(offset - lineStarts_[line - 1] + 1)};
  }
  SourcePos here() const { return posAt(p_); }
  [[noreturn]] void error(size_t offset, const std::string& message) const {
    SourcePos pos = posAt(std::min(offset, t_.size()));
    throw Error(source_, fmt::format("{}:{}", pos.line, pos.col), message);
  }
  [[noreturn]] void unexpected(const std::string& expected) const {
    error(p_, fmt::format("expected {}, found {}", expected, describeChar(peek())));
  }
  bool lineStartsWith(const char* s) const { return t_.compare(p_, std::strlen(s), s) == 0; }

  // Skips spaces, tabs, carriage returns and comments (# to the end of the line, /* */);
  // newlines too when `newlines`.
  void skipBlank(bool newlines = false) {
    for (;;) {
      int c = peek();
      if (c == ' ' || c == '\t' || c == '\r' || (newlines && c == '\n')) {
        ++p_;
      } else if (c == '#' && !lineStartsWith("#define") && !preprocessorLine()) {
        while (!eof() && peek() != '\n') ++p_;
      } else if (c == '/' && peek(1) == '*') {
        size_t start = p_;
        size_t close = t_.find("*/", p_ + 2);
        if (close == std::string_view::npos) error(start, "comment /* is never closed");
        p_ = close + 2;
      } else {
        return;
      }
    }
  }
  // cpfg's preprocessor lines other than #define (#include, #ifdef, ...) are reported, not
  // skipped as comments.
  bool preprocessorLine() const {
    for (const char* d : {"#include", "#if", "#else", "#elif", "#endif", "#undef", "#pragma"})
      if (lineStartsWith(d)) return true;
    return false;
  }

  bool atLineEnd() {
    skipBlank();
    return eof() || peek() == '\n';
  }
  void expectLineEnd() {
    if (!atLineEnd()) unexpected("the end of the line");
    if (!eof()) ++p_;
  }
  bool isArrowHere() const {
    return (peek() == '-' && peek(1) == '>') || (peek() == '-' && peek(1) == '-' && peek(2) == '>');
  }
  std::string identifier() {
    size_t start = p_;
    while (isIdentChar(peek())) ++p_;
    return std::string(t_.substr(start, p_ - start));
  }
  void enter() {
    if (++nesting_ > kMaxNesting) error(p_, fmt::format("nested more than {} levels deep", kMaxNesting));
  }
  void leave() { --nesting_; }
  // Inside parentheses expressions may continue over several lines.
  struct ParenScope {
    explicit ParenScope(Parser& parser) : p(parser), base(parser.parenBase_) {
      p.enter();
      p.parenBase_ = -1;
    }
    ~ParenScope() {
      p.parenBase_ = base;
      p.leave();
    }
    Parser& p;
    int base;
  };

  // --- directives ---------------------------------------------------------------------

  bool tryEndLSystem() {
    size_t q = p_;
    std::string w;
    while (q < t_.size() && isIdentChar(static_cast<unsigned char>(t_[q]))) w += char(std::tolower(t_[q++]));
    if (w != "endlsystem") return false;
    p_ = q;
    expectLineEnd();
    return true;  // the rest of the file is not read (as in L-Py)
  }

  // A line of words followed by ':' is a directive. Returns false for productions.
  bool tryDirective() {
    size_t q = p_;
    std::string key;
    bool space = false;
    while (q < t_.size()) {
      int c = static_cast<unsigned char>(t_[q]);
      if (isIdentChar(c)) {
        if (space && !key.empty()) key += ' ';
        space = false;
        key += c == '_' ? ' ' : char(std::tolower(c));
      } else if (c == ' ' || c == '\t') {
        space = true;
      } else {
        break;
      }
      ++q;
    }
    if (q >= t_.size() || t_[q] != ':' || key.empty() || isDigit(static_cast<unsigned char>(key[0]))) return false;
    for (const DirectiveName& d : kDirectives) {
      if (key == d.text) {
        size_t at = p_;
        p_ = q + 1;
        directive(d.d, at);
        return true;
      }
    }
    // Not a directive: a production such as `A : x > 1 -> B` has an arrow on its line.
    size_t eol = t_.find('\n', q);
    std::string_view rest = t_.substr(q, eol == std::string_view::npos ? std::string_view::npos : eol - q);
    if (rest.find("->") != std::string_view::npos) return false;
    std::string best;
    size_t bestDistance = 3;
    for (const DirectiveName& d : kDirectives) {
      size_t dist = editDistance(key, d.text);
      if (dist < bestDistance) {
        bestDistance = dist;
        best = d.text;
      }
    }
    error(p_, fmt::format("unknown directive \"{}:\"{}", key, best.empty() ? "" : fmt::format(" (did you mean \"{}:\"?)", best)));
  }

  Setting<ExprPtr> exprSetting() {
    skipBlank();
    Setting<ExprPtr> s{nullptr, here()};
    s.value = expression();
    expectLineEnd();
    return s;
  }

  template <class T>
  void once(std::optional<T>& slot, T value, size_t at, const char* what) {
    if (slot) error(at, fmt::format("{} is given twice", what));
    slot = std::move(value);
  }

  void directive(Directive d, size_t at) {
    switch (d) {
      case Directive::LSystem: {
        skipBlank();
        size_t start = p_;
        while (!eof() && peek() != '\n' && peek() != '#') ++p_;
        std::string_view name = t_.substr(start, p_ - start);
        while (!name.empty() && (name.back() == ' ' || name.back() == '\t' || name.back() == '\r')) name.remove_suffix(1);
        g_.name = std::string(name);
        expectLineEnd();
        break;
      }
      case Directive::Seed: once(g_.seed, exprSetting(), at, "seed:"); break;
      case Directive::DerivationLength: once(g_.derivationLength, exprSetting(), at, "derivation length:"); break;
      case Directive::MaxLength: once(g_.maxLength, exprSetting(), at, "max length:"); break;
      case Directive::Angle: once(g_.angle, exprSetting(), at, "angle:"); break;
      case Directive::Step: once(g_.step, exprSetting(), at, "step:"); break;
      case Directive::Width: once(g_.width, exprSetting(), at, "width:"); break;
      case Directive::WidthFactor: once(g_.widthFactor, exprSetting(), at, "width factor:"); break;
      case Directive::Elasticity: once(g_.elasticity, exprSetting(), at, "elasticity:"); break;
      case Directive::LeafThickness: once(g_.leafThickness, exprSetting(), at, "leaf thickness:"); break;
      case Directive::Tropism: {
        skipBlank();
        SourcePos pos = here();
        once(g_.tropism, Setting<std::vector<ExprPtr>>{vector3(), pos}, at, "tropism:");
        expectLineEnd();
        break;
      }
      case Directive::Define:
      case Directive::Global: {
        auto& list = d == Directive::Define ? g_.defines : g_.globals;
        do {
          skipBlank();
          Assignment a;
          a.pos = here();
          if (!isIdentStart(peek())) unexpected("a name");
          a.name = identifier();
          skipBlank();
          if (peek() != '=' || peek(1) == '=') unexpected("'='");
          ++p_;
          skipBlank();
          a.value = expression();
          list.push_back(std::move(a));
          skipBlank();
        } while (peek() == ',' && ++p_);
        expectLineEnd();
        break;
      }
      case Directive::Module: {
        do {
          skipBlank();
          ModuleDecl m;
          m.pos = here();
          if (!isIdentStart(peek())) unexpected("a module name");
          m.name = identifier();
          skipBlank();
          if (peek() == '(') {
            ++p_;
            int n = 0;
            skipBlank(true);
            if (peek() != ')') {
              do {
                skipBlank(true);
                if (!isIdentStart(peek())) unexpected("a parameter name");
                identifier();
                ++n;
                skipBlank(true);
              } while (peek() == ',' && ++p_);
            }
            if (peek() != ')') unexpected("')'");
            ++p_;
            m.arity = n;
          }
          if (std::find(declared_.begin(), declared_.end(), m.name) == declared_.end()) declared_.push_back(m.name);
          g_.moduleDecls.push_back(std::move(m));
          skipBlank();
        } while (peek() == ',' && ++p_);
        expectLineEnd();
        break;
      }
      case Directive::Ignore:
      case Directive::Consider: {
        if (g_.ignore || g_.consider) error(at, "give either one ignore: or one consider: list");
        skipBlank();
        ModuleString s = modules(false);
        (d == Directive::Ignore ? g_.ignore : g_.consider) = std::move(s);
        expectLineEnd();
        break;
      }
      case Directive::Axiom: {
        skipBlank();
        SourcePos pos = here();
        once(g_.axiom, Setting<ModuleString>{modules(false), pos}, at, "axiom:");
        expectLineEnd();
        break;
      }
      case Directive::LeafShapes: {
        do {
          skipBlank();
          LeafShapeDecl s;
          s.pos = here();
          s.texture = stringLiteral();
          skipBlank();
          if (peek() != ',' && peek() != '\n' && !eof()) s.aspect = expression();
          g_.leafShapes.push_back(std::move(s));
          skipBlank();
        } while (peek() == ',' && ++p_);
        expectLineEnd();
        break;
      }
      case Directive::Colors: {
        do {
          skipBlank();
          SourcePos pos = here();
          g_.colors.push_back({vector3(true), pos});
          skipBlank();
        } while (peek() == ',' && ++p_);
        expectLineEnd();
        break;
      }
      case Directive::Bark: {
        skipBlank();
        SourcePos pos = here();
        once(g_.barkTexture, Setting<std::string>{stringLiteral(), pos}, at, "bark:");
        skipBlank();
        if (peek() == '(') {
          pos = here();
          g_.barkColor = Setting<std::vector<ExprPtr>>{vector3(true), pos};
        }
        expectLineEnd();
        break;
      }
      case Directive::Surface: {
        skipBlank();
        SurfaceDecl s;
        s.pos = here();
        if (!isIdentStart(peek())) unexpected("a surface name");
        s.name = identifier();
        if (s.name == kLeafSurface) error(posOffset(s.pos), "~leaf is the built-in leaf; choose another surface name");
        for (const SurfaceDecl& o : g_.surfaces)
          if (o.name == s.name) error(posOffset(s.pos), fmt::format("surface \"{}\" is defined twice", s.name));
        skipBlank();
        if (peek() != '=') unexpected("'=' and the surface's turtle string");
        ++p_;
        skipBlank();
        s.body = modules(false);
        g_.surfaces.push_back(std::move(s));
        surfaces_.push_back(g_.surfaces.back().name);
        expectLineEnd();
        break;
      }
      case Directive::Start: blockDirective(g_.start, 0, at, "Start:"); break;
      case Directive::StartEach: blockDirective(g_.startEach, 1, at, "StartEach:"); break;
      case Directive::EndEach: blockDirective(g_.endEach, 2, at, "EndEach:"); break;
      case Directive::End: blockDirective(g_.end, 3, at, "End:"); break;
      case Directive::Production: section_ = Section::Production; expectLineEnd(); break;
      case Directive::Decomposition: section_ = Section::Decomposition; expectLineEnd(); break;
      case Directive::Interpretation: section_ = Section::Interpretation; expectLineEnd(); break;
      case Directive::MaximumDepth: {
        if (section_ == Section::Production)
          error(at, "maximum depth: belongs to a decomposition: or interpretation: section");
        once(g_.maxDepth[size_t(section_)], exprSetting(), at, "maximum depth:");
        break;
      }
    }
  }

  size_t posOffset(SourcePos pos) const { return lineStarts_[pos.line - 1] + pos.col - 1; }

  void blockDirective(std::vector<Stmt>& out, int which, size_t at, const char* what) {
    if (blockSeen_[which]) error(at, fmt::format("{} is given twice", what));
    blockSeen_[which] = true;
    skipBlank(true);
    out = block();
    expectLineEnd();
  }

  // `#define NAME value` (cpfg).
  void parseHashDefine() {
    p_ += std::strlen("#define");
    if (peek() != ' ' && peek() != '\t') unexpected("a space after #define");
    skipBlank();
    Assignment a;
    a.pos = here();
    if (!isIdentStart(peek())) unexpected("a name");
    a.name = identifier();
    skipBlank();
    a.value = expression();
    g_.defines.push_back(std::move(a));
    expectLineEnd();
  }

  std::string stringLiteral() {
    if (peek() != '"') unexpected("a quoted string");
    size_t start = p_++;
    std::string s;
    for (;;) {
      int c = peek();
      if (c < 0 || c == '\n') error(start, "string is not closed with \"");
      ++p_;
      if (c == '"') break;
      if (c == '\\' && (peek() == '"' || peek() == '\\')) c = t_[p_++];
      s += char(c);
    }
    return s;
  }

  // "(x, y, z)" (parentheses optional unless `parens`).
  std::vector<ExprPtr> vector3(bool parens = false) {
    bool open = peek() == '(';
    if (parens && !open) unexpected("'(' and three numbers");
    std::vector<ExprPtr> v;
    std::optional<ParenScope> scope;
    if (open) {
      ++p_;
      scope.emplace(*this);
    }
    for (int i = 0; i < 3; ++i) {
      if (i > 0) {
        skipBlank(open);
        if (peek() != ',') unexpected("',' and three numbers");
        ++p_;
      }
      skipBlank(open);
      v.push_back(expression());
    }
    if (open) {
      skipBlank(true);
      if (peek() != ')') unexpected("')'");
      ++p_;
    }
    return v;
  }

  // --- productions --------------------------------------------------------------------

  void parseProduction() {
    syntax::Production pr;
    pr.section = section_;
    size_t start = p_;
    pr.pos = here();
    ModuleString first = modules(true);
    skipBlank();
    if (peek() == '<') {
      ++p_;
      pr.left = std::move(first);
      pr.hasLeft = true;
      skipBlank();
      first = modules(true);
      skipBlank();
    }
    if (first.modules.size() != 1) {
      if (first.modules.empty()) unexpected("a module to rewrite (the predecessor)");
      error(posOffset(first.modules[1].pos),
            fmt::format("a production rewrites exactly one module (its strict predecessor), here {} are written; "
                        "use < and > for context",
                        first.modules.size()));
    }
    pr.pred = std::move(first.modules[0]);
    if (peek() == '>') {
      ++p_;
      skipBlank();
      pr.right = modules(true);
      pr.hasRight = true;
      skipBlank();
    }
    if (peek() == ':') {
      ++p_;
      skipBlank(true);
      if (peek() == '{') {
        pr.pre = block();
        skipBlank(true);
      }
      if (peek() == '*') {
        ++p_;
        skipBlank(true);
      } else if (!isArrowHere() && peek() != '{') {
        pr.condition = expression();
        skipBlank(true);
      }
      if (peek() == '{') {
        pr.post = block();
        skipBlank(true);
      }
    }
    if (!isArrowHere()) {
      if (!pr.hasLeft && !pr.hasRight && peek() == '=')
        unexpected("-> (productions are written `A -> B`)");
      unexpected("-> or -->");
    }
    p_ += peek(1) == '>' ? 2 : 3;
    skipBlank();
    if (peek() == '*') {
      ++p_;
      pr.successor.pos = here();
    } else {
      pr.successor = modules(false);
    }
    skipBlank();
    if (peek() == ':') {
      ++p_;
      skipBlank();
      pr.probability = expression();
    }
    size_t end = p_;
    expectLineEnd();
    pr.text = productionText(start, end);
    g_.productions.push_back(std::move(pr));
  }

  std::string productionText(size_t start, size_t end) const {
    std::string s;
    bool space = false;
    for (size_t i = start; i < end; ++i) {
      char c = t_[i];
      if (c == '\n' || c == '\r' || c == '\t' || c == ' ') {
        space = !s.empty();
        continue;
      }
      if (space) s += ' ';
      space = false;
      s += c;
    }
    if (s.size() > 160) s = s.substr(0, 157) + "...";
    return s;
  }

  // A module string: stops before anything that cannot start a module (line end, < > : = *
  // and the arrow). Patterns take formal parameter names in their lists.
  ModuleString modules(bool pattern) {
    ModuleString s;
    s.pos = here();
    for (;;) {
      skipBlank();
      int c = peek();
      if (c < 0 || c == '\n' || isArrowHere()) break;
      size_t start = p_;
      Module m;
      m.pos = here();
      if (c == '@') {
        ++p_;
        m.name = "@" + longest(std::begin(kAtModules), std::end(kAtModules), start, "turtle module",
                               "R, M, Tv, Te, O, Climb");
      } else if (c == '?') {
        ++p_;
        int q = peek();
        if (q != 'P' && q != 'H' && q != 'U' && q != 'L' && q != 'E')
          error(start, "unknown query module (known: ?P, ?H, ?U, ?L, ?E)");
        ++p_;
        m.name = std::string("?") + char(q);
      } else if (c == '~') {
        ++p_;
        std::vector<std::string_view> names{kLeafSurface};
        for (const std::string& n : surfaces_) names.push_back(n);
        std::string known = "leaf";
        for (const std::string& n : surfaces_) known += ", " + n;
        m.name = "~" + longest(names.begin(), names.end(), start, "surface", known);
      } else if (isIdentStart(c)) {
        size_t best = 0;
        for (const std::string& n : declared_)
          if (n.size() > best && t_.compare(p_, n.size(), n) == 0) best = n.size();
        if (best == 0) {
          if (c == '_') error(start, "'_' cannot start a module name; declare names with module:");
          best = 1;
        }
        m.name = std::string(t_.substr(p_, best));
        p_ += best;
      } else if (isTurtleSymbol(c)) {
        m.name = std::string(1, char(c));
        ++p_;
      } else if (isDigit(c)) {
        m.name = std::string(1, char(c));  // ABOP's 0 and 1 (§1.8) are modules too
        ++p_;
      } else {
        break;
      }
      skipBlank();
      if (peek() == '(') {
        m.parens = true;
        ++p_;
        ParenScope scope(*this);
        skipBlank(true);
        if (peek() != ')') {
          for (;;) {
            skipBlank(true);
            if (pattern) {
              auto e = std::make_unique<Expr>();
              e->kind = Expr::Kind::Name;
              e->pos = here();
              if (!isIdentStart(peek())) unexpected("a parameter name (patterns bind names)");
              e->name = identifier();
              m.args.push_back(std::move(e));
            } else {
              m.args.push_back(expression());
            }
            skipBlank(true);
            if (peek() != ',') break;
            ++p_;
          }
        }
        if (peek() != ')') unexpected("',' or ')'");
        ++p_;
        if (m.args.size() > 255) error(start, "a module has at most 255 parameters");
      }
      s.modules.push_back(std::move(m));
    }
    return s;
  }

  // The longest of `names` at the current position.
  template <class It>
  std::string longest(It begin, It end, size_t start, const char* what, const std::string& known) {
    size_t best = 0;
    for (It i = begin; i != end; ++i) {
      std::string_view n = *i;
      if (n.size() > best && t_.compare(p_, n.size(), n) == 0) best = n.size();
    }
    if (best == 0) {
      size_t q = p_;
      while (q < t_.size() && isIdentChar(static_cast<unsigned char>(t_[q]))) ++q;
      error(start, fmt::format("unknown {} \"{}{}\" (known: {})", what, t_[start], t_.substr(p_, q - p_), known));
    }
    std::string s(t_.substr(p_, best));
    p_ += best;
    return s;
  }

  // --- statements ---------------------------------------------------------------------

  std::vector<Stmt> block() {
    if (peek() != '{') unexpected("'{'");
    size_t open = p_++;
    enter();
    std::vector<Stmt> out;
    for (;;) {
      skipBlank(true);
      if (eof()) error(open, "block { is never closed");
      if (peek() == '}') {
        ++p_;
        break;
      }
      if (peek() == ';') {
        ++p_;
        continue;
      }
      out.push_back(statement());
    }
    leave();
    return out;
  }

  Stmt statement() {
    Stmt s;
    s.pos = here();
    if (peek() == '{') {
      s.kind = Stmt::Kind::Block;
      s.body = block();
      return s;
    }
    if (!isIdentStart(peek())) unexpected("a statement (name = value;, if (...) ... else ...)");
    size_t start = p_;
    std::string word = identifier();
    if (word == "if") {
      s.kind = Stmt::Kind::If;
      skipBlank(true);
      if (peek() != '(') unexpected("'(' after if");
      s.value = expression();  // a parenthesised expression
      skipBlank(true);
      enter();
      s.body = branch();
      size_t save = p_;
      skipBlank(true);
      if (t_.compare(p_, 4, "else") == 0 && !isIdentChar(peek(4))) {
        p_ += 4;
        skipBlank(true);
        s.otherwise = branch();
      } else {
        p_ = save;
      }
      leave();
      return s;
    }
    if (word == "else") error(start, "else without if");
    s.kind = Stmt::Kind::Assign;
    s.name = word;
    skipBlank();
    int c = peek();
    if ((c == '+' || c == '-' || c == '*' || c == '/') && peek(1) == '=') {
      s.op = char(c);
      p_ += 2;
    } else if (c == '=' && peek(1) != '=') {
      ++p_;
    } else {
      unexpected(fmt::format("'=' after {}", word));
    }
    skipBlank();
    s.value = expression();
    skipBlank();
    if (peek() == ';') ++p_;
    else if (peek() != '\n' && peek() != '}' && !eof()) unexpected("';'");
    return s;
  }

  std::vector<Stmt> branch() {
    if (peek() == '{') return block();
    std::vector<Stmt> v;
    v.push_back(statement());
    return v;
  }

  // --- expressions --------------------------------------------------------------------

  ExprPtr node(Expr::Kind kind, SourcePos pos) {
    auto e = std::make_unique<Expr>();
    e->kind = kind;
    e->pos = pos;
    return e;
  }

  ExprPtr expression() {
    enter();
    ExprPtr e = ternary();
    leave();
    return e;
  }

  void blank() { skipBlank(nesting_ > parenBase_); }

  ExprPtr ternary() {
    ExprPtr c = logicalOr();
    blank();
    if (peek() != '?') return c;
    SourcePos pos = here();
    ++p_;
    blank();
    auto e = node(Expr::Kind::Ternary, pos);
    e->args.push_back(std::move(c));
    enter();
    e->args.push_back(ternary());
    blank();
    if (peek() != ':') unexpected("':' of the ?: expression");
    ++p_;
    blank();
    e->args.push_back(ternary());
    leave();
    return e;
  }

  // Each further operand of a chain such as a + b + c deepens the tree: it counts as nesting.
  struct ChainDepth {
    explicit ChainDepth(Parser& parser) : p(parser) {}
    ~ChainDepth() { p.nesting_ -= n; }
    void next() {
      p.enter();
      ++n;
    }
    Parser& p;
    int n = 0;
  };

  // A left-associative chain of a doubled operator (|| or &&) over `operand`.
  ExprPtr logicalChain(char c, Expr::Kind kind, ExprPtr (Parser::*operand)()) {
    ExprPtr l = (this->*operand)();
    ChainDepth chain(*this);
    for (;;) {
      blank();
      if (!(peek() == c && peek(1) == c)) return l;
      chain.next();
      SourcePos pos = here();
      p_ += 2;
      blank();
      auto e = node(kind, pos);
      e->args.push_back(std::move(l));
      e->args.push_back((this->*operand)());
      l = std::move(e);
    }
  }

  ExprPtr logicalOr() { return logicalChain('|', Expr::Kind::Or, &Parser::logicalAnd); }
  ExprPtr logicalAnd() { return logicalChain('&', Expr::Kind::And, &Parser::comparison); }

  ExprPtr binary(char op, SourcePos pos, ExprPtr l, ExprPtr r) {
    auto e = node(Expr::Kind::Binary, pos);
    e->op = op;
    e->args.push_back(std::move(l));
    e->args.push_back(std::move(r));
    return e;
  }

  ExprPtr comparison() {
    ExprPtr l = additive();
    ChainDepth chain(*this);
    for (;;) {
      blank();
      int c = peek(), d = peek(1);
      char op = 0;
      size_t len = 1;
      if (c == '<' && d == '=') op = 'L', len = 2;
      else if (c == '>' && d == '=') op = 'G', len = 2;
      else if (c == '=' && d == '=') op = '=', len = 2;
      else if (c == '!' && d == '=') op = 'N', len = 2;
      else if (c == '<') op = '<';
      else if (c == '>') op = '>';
      else return l;
      chain.next();
      SourcePos pos = here();
      p_ += len;
      blank();
      l = binary(op, pos, std::move(l), additive());
    }
  }

  ExprPtr additive() {
    ExprPtr l = multiplicative();
    ChainDepth chain(*this);
    for (;;) {
      blank();
      int c = peek();
      if ((c != '+' && c != '-') || isArrowHere()) return l;
      chain.next();
      SourcePos pos = here();
      ++p_;
      blank();
      l = binary(char(c), pos, std::move(l), multiplicative());
    }
  }

  ExprPtr multiplicative() {
    ExprPtr l = unary();
    ChainDepth chain(*this);
    for (;;) {
      blank();
      int c = peek();
      if (c == '*' && peek(1) == '*') return l;  // power, handled below unary
      if (c != '*' && c != '/' && c != '%') return l;
      if (c == '/' && peek(1) == '*') return l;  // a comment
      chain.next();
      SourcePos pos = here();
      ++p_;
      blank();
      l = binary(char(c), pos, std::move(l), unary());
    }
  }

  ExprPtr unary() {
    blank();
    int c = peek();
    if ((c == '-' && !isArrowHere()) || c == '+' || (c == '!' && peek(1) != '=')) {
      SourcePos pos = here();
      ++p_;
      enter();
      ExprPtr operand = unary();
      leave();
      if (c == '+') return operand;
      auto e = node(Expr::Kind::Unary, pos);
      e->op = char(c);
      e->args.push_back(std::move(operand));
      return e;
    }
    return power();
  }

  ExprPtr power() {
    ExprPtr base = primary();
    blank();
    if (peek() == '^' || (peek() == '*' && peek(1) == '*')) {
      SourcePos pos = here();
      p_ += peek() == '^' ? 1 : 2;
      enter();
      ExprPtr exponent = unary();  // right-associative: 2^3^2 = 2^9; -2^2 = -4
      leave();
      return binary('^', pos, std::move(base), std::move(exponent));
    }
    return base;
  }

  ExprPtr primary() {
    blank();
    int c = peek();
    SourcePos pos = here();
    if (isDigit(c) || (c == '.' && isDigit(peek(1)))) {
      size_t start = p_;
      while (isDigit(peek())) ++p_;
      if (peek() == '.') {
        ++p_;
        while (isDigit(peek())) ++p_;
      }
      if ((peek() == 'e' || peek() == 'E') &&
          (isDigit(peek(1)) || ((peek(1) == '+' || peek(1) == '-') && isDigit(peek(2))))) {
        p_ += 2;
        while (isDigit(peek())) ++p_;
      }
      if (isIdentChar(peek())) error(p_, fmt::format("unexpected {} after a number", describeChar(peek())));
      auto e = node(Expr::Kind::Number, pos);
      const char* b = t_.data() + start;
      auto r = std::from_chars(b, t_.data() + p_, e->value);
      if (r.ec != std::errc() || !std::isfinite(e->value)) error(start, "number out of range");
      return e;
    }
    if (isIdentStart(c)) {
      std::string name = identifier();
      size_t save = p_;
      skipBlank();
      if (peek() == '(') {
        ++p_;
        auto e = node(Expr::Kind::Call, pos);
        e->name = std::move(name);
        ParenScope scope(*this);
        skipBlank(true);
        if (peek() != ')') {
          for (;;) {
            skipBlank(true);
            e->args.push_back(ternary());
            skipBlank(true);
            if (peek() != ',') break;
            ++p_;
          }
        }
        if (peek() != ')') unexpected("',' or ')'");
        ++p_;
        return e;
      }
      p_ = save;
      auto e = node(Expr::Kind::Name, pos);
      e->name = std::move(name);
      return e;
    }
    if (c == '(') {
      ++p_;
      ParenScope scope(*this);
      skipBlank(true);
      ExprPtr e = ternary();
      skipBlank(true);
      if (peek() != ')') unexpected("')'");
      ++p_;
      return e;
    }
    unexpected("a number, a name or '('");
  }

  std::string_view t_;
  std::string source_;
  std::vector<size_t> lineStarts_;
  size_t p_ = 0;
  int nesting_ = 0;
  // Newlines are skipped inside an expression when nesting_ > parenBase_: inside parentheses
  // (parenBase_ = -1) always, at the top level of a directive or condition never.
  int parenBase_ = kMaxNesting + 1;
  Section section_ = Section::Production;
  std::vector<std::string> declared_;  // multi-character module names from module:
  std::vector<std::string> surfaces_;
  bool blockSeen_[4] = {false, false, false, false};
  syntax::Grammar g_;
};

}  // namespace

syntax::Grammar parseGrammar(std::string_view text, const std::string& source) {
  return Parser(text, source).parse();
}

}  // namespace tendril::lsystem

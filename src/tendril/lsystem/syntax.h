// The syntax tree of a grammar file, as the parser reads it (parser.cpp) and before names are
// resolved (compiler.cpp). Only the parser and the compiler use it.
#pragma once

#include "tendril/lsystem/grammar.h"

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace tendril::lsystem::syntax {

struct Expr;
using ExprPtr = std::unique_ptr<Expr>;

struct Expr {
  enum class Kind { Number, Name, Unary, Binary, Call, Ternary, And, Or };
  Kind kind = Kind::Number;
  SourcePos pos;
  double value = 0.0;
  std::string name;  // Name, Call
  char op = 0;       // Unary: '-', '!'; Binary: + - * / % ^ < L(<=) > G(>=) = (==) N (!=)
  std::vector<ExprPtr> args;
};

struct Stmt {
  enum class Kind { Assign, If, Block };
  Kind kind = Kind::Assign;
  SourcePos pos;
  std::string name;  // Assign: the variable
  char op = '=';     // '=', or + - * / for compound assignment
  ExprPtr value;     // Assign: the value; If: the condition
  std::vector<Stmt> body, otherwise;  // If branches, Block body
};

struct Module {
  std::string name;
  SourcePos pos;
  bool parens = false;        // written with a parameter list
  std::vector<ExprPtr> args;  // patterns: Name expressions (formal parameters)
};

struct ModuleString {
  SourcePos pos;
  std::vector<Module> modules;
};

struct Production {
  Section section = Section::Production;
  SourcePos pos;
  std::string text;
  ModuleString left, right;
  bool hasLeft = false, hasRight = false;
  Module pred;
  std::vector<Stmt> pre, post;
  ExprPtr condition;  // null: always
  ModuleString successor;
  ExprPtr probability;  // null: not stochastic
};

struct Assignment {  // define:, global:
  std::string name;
  SourcePos pos;
  ExprPtr value;
};

struct ModuleDecl {
  std::string name;
  SourcePos pos;
  std::optional<int> arity;  // declared parameter count, if a list was given
};

struct LeafShapeDecl {
  std::string texture;
  SourcePos pos;
  ExprPtr aspect;  // null: 1
};

struct SurfaceDecl {
  std::string name;
  SourcePos pos;
  ModuleString body;
};

template <class T>
struct Setting {  // a directive's value with where it was written
  T value;
  SourcePos pos;
};

struct Grammar {
  std::string name;
  std::optional<Setting<ExprPtr>> seed, derivationLength, maxLength;
  std::optional<Setting<ExprPtr>> angle, step, width, widthFactor, elasticity, leafThickness;
  std::optional<Setting<std::vector<ExprPtr>>> tropism;
  std::vector<Assignment> defines, globals;
  std::vector<ModuleDecl> moduleDecls;
  std::optional<ModuleString> ignore, consider;
  std::optional<Setting<ModuleString>> axiom;
  std::vector<LeafShapeDecl> leafShapes;
  std::vector<Setting<std::vector<ExprPtr>>> colors;
  std::optional<Setting<std::string>> barkTexture;
  std::optional<Setting<std::vector<ExprPtr>>> barkColor;
  std::vector<SurfaceDecl> surfaces;
  std::vector<Stmt> start, startEach, endEach, end;
  std::array<std::optional<Setting<ExprPtr>>, kSectionCount> maxDepth;
  std::vector<Production> productions;
};

}  // namespace tendril::lsystem::syntax

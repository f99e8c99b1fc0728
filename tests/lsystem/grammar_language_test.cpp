// The grammar language: syntax familiar from cpfg and L-Py, and an error for every kind of
// mistake, located at file:line:col with the line and a caret.
#include "lsystem/lsystem_test_util.h"

#include <gtest/gtest.h>

namespace tendril::lsystem {
namespace {

using test::compile;
using test::derived;
using test::errorOf;

TEST(GrammarLanguage, CpfgAndLPySyntax) {
  // Directive names in any case, #define, comments of both kinds, -->, * for "no condition"
  // and for the empty successor, parameters over several lines, multi-letter modules,
  // a production: header and endlsystem.
  const char* g = R"(
lsystem: syntax-tour
#define N 3
/* a block
   comment */
Derivation Length: N   # a line comment
module: Apex(len), Leaf
Axiom: Apex(1) X Leaf
production:
Apex(l) : * --> F(l) Apex(l +
                        1)
X --> *
Leaf : * -> Leaf Leaf
endlsystem
this text after endlsystem is not read
)";
  LSystem ls(compile(g));
  EXPECT_EQ(ls.grammar().name, "syntax-tour");
  ls.derive();
  EXPECT_EQ(ls.text(), "F(1)F(2)F(3) Apex(4) Leaf Leaf Leaf Leaf Leaf Leaf Leaf Leaf");
}

TEST(GrammarLanguage, DefinesCanBeOverridden) {
  auto g = compile("define: n = 2, m = n * 3\naxiom: A(m)\n", test::defines({{"n", 5}}));
  LSystem ls(g);
  EXPECT_EQ(ls.text(), "A(15)");
}

TEST(GrammarLanguage, TurtleSettings) {
  auto g = compile("angle: 45\nstep: 2\nwidth: 0.3\nwidth factor: 0.9\ntropism: (0, -1, 0)\nelasticity: 0.1\n"
                   "leaf shapes: \"builtin:ivy-0\" 1.0, \"builtin:heart-0\" 0.8\ncolors: (1, 0, 0)\n"
                   "bark: \"builtin:bark\" (0.5, 0.4, 0.3)\nleaf thickness: 0.001\naxiom: F\n");
  EXPECT_FLOAT_EQ(g->turtle.angle, radians(45.0f));
  EXPECT_FLOAT_EQ(g->turtle.step, 2.0f);
  EXPECT_FLOAT_EQ(g->turtle.width, 0.3f);
  EXPECT_FLOAT_EQ(g->turtle.widthFactor, 0.9f);
  EXPECT_EQ(g->turtle.tropism, Vec3(0, -1, 0));
  EXPECT_FLOAT_EQ(g->turtle.elasticity, 0.1f);
  ASSERT_EQ(g->leafShapes.size(), 2u);
  EXPECT_EQ(g->leafShapes[1].texture, "builtin:heart-0");
  EXPECT_FLOAT_EQ(g->leafShapes[1].aspect, 0.8f);
  ASSERT_EQ(g->colors.size(), 1u);
  EXPECT_EQ(g->bark.color, Vec3(0.5f, 0.4f, 0.3f));
  EXPECT_FLOAT_EQ(g->turtle.leafThickness, 0.001f);
}

// --- errors at compile time: file:line:col, one line ---------------------------------

struct CompileErrorCase {
  const char* text;
  const char* message;
};

TEST(GrammarErrors, SyntaxAndMeaningErrorsNameLineAndColumn) {
  const CompileErrorCase cases[] = {
      {"axiom: A\nA -> B(1 +)\n", "test.ls:2:11: expected a number, a name or '(', found ')'"},
      {"derivaton length: 5\naxiom: A\n",
       "test.ls:1:1: unknown directive \"derivaton length:\" (did you mean \"derivation length:\"?)"},
      {"axiom: A\nA B -> C\n",
       "test.ls:2:3: a production rewrites exactly one module (its strict predecessor), here 2 are written; use < "
       "and > for context"},
      {"axiom: A\nA => B\n", "test.ls:2:3: expected -> (productions are written `A -> B`), found '='"},
      {"define: fool = 1\naxiom: A(foo)\n", "test.ls:2:10: unknown name \"foo\" (did you mean \"fool\"?)"},
      {"axiom: A(sine(30))\n", "test.ls:1:10: unknown function sine() (did you mean \"sin\"?)"},
      {"axiom: A(sin(1, 2))\n", "test.ls:1:10: sin() takes 1 argument, got 2"},
      {"axiom: A(1) B\nB -> A(1, 2)\n",
       "test.ls:2:6: module A has 2 parameters here but 1 where it is first used at 1:8 (a module keeps its number "
       "of parameters)"},
      {"axiom: F(1, 2)\n", "test.ls:1:8: F takes 0 or 1 parameter, 2 here in the axiom"},
      {"axiom: @Q\n", "test.ls:1:8: unknown turtle module \"@Q\" (known: R, M, Tv, Te, O, Climb)"},
      {"axiom: ?X\n", "test.ls:1:8: unknown query module (known: ?P, ?H, ?U, ?L, ?E)"},
      {"axiom: ~petal\n", "test.ls:1:8: unknown surface \"~petal\" (known: leaf)"},
      {"ignore: Q\naxiom: A\n", "test.ls:1:9: unknown module Q: no axiom, successor or production uses it"},
      {"axiom: A\nA -> [B\n", "test.ls:2:6: the production opens 1 more [ than it closes"},
      {"axiom: A\nA -> B]\n", "test.ls:2:7: ] without a matching [ in the production"},
      {"axiom: A(1)\nA(x) : { x = 2; } -> A(x)\n",
       "test.ls:2:10: cannot assign to the parameter \"x\" (assign to a new local name)"},
      {"axiom: A B\n[A < B -> C\n", "test.ls:2:1: a left context cannot contain brackets"},
      {"axiom: A\n[ -> A\n", "test.ls:2:1: brackets cannot be rewritten (they keep the string's branches balanced)"},
      {"axiom: ?E(LIGHT, 0, 0, 0, 0, 0)\n", "test.ls:1:11: ?E(LIGHT, ...) takes 1 to 5 parameters, 6 here"},
      {"axiom: ?E(9, 0)\n", "test.ls:1:11: unknown ?E query kind 9 (SURFACE, HIT, LIGHT, ATTRACT or FACING)"},
      {"axiom: A\ndecomposition:\nA < B -> C\n", "test.ls:3:1: a decomposition rule cannot have a context (only "
                                                  "productions can)"},
      {"global: g = 0\naxiom: A\ninterpretation:\nA : { g = 1; } -> F\n",
       "test.ls:4:7: interpretation rules cannot assign the global variable \"g\" (interpretation must not change "
       "the L-system)"},
      {"derivation length: n\naxiom: A\n", "test.ls:1:20: unknown name \"n\""},
      {"derivation length: 2.5\naxiom: A\n", "test.ls:1:20: derivation length must be a whole number, got 2.5"},
      {"angle: 1/0\naxiom: A\n", "test.ls:1:9: division by zero"},
      {"A -> B\n", "test.ls: the grammar has no axiom: (the string derivation starts from)"},
      {"axiom: A\naxiom: B\n", "test.ls:2:1: axiom: is given twice"},
      {"axiom: A\ndecomposition:\nmaximum depth: 5000\n", "test.ls:3:16: maximum depth must lie in [1, 1000], got 5000"},
      {"axiom: A\nmaximum depth: 3\n",
       "test.ls:2:1: maximum depth: belongs to a decomposition: or interpretation: section"},
      {"leaf shapes: \"builtin:fern\"\naxiom: A\n",
       "test.ls:1:14: unknown built-in texture \"builtin:fern\" (known: ivy-0, ivy-1, ivy-2, heart-0, ovate-0, bark)"},
      {"axiom: A /* never closed\n", "test.ls:1:10: comment /* is never closed"},
      {"#include \"x.l\"\naxiom: A\n", "test.ls:1:1: only #define is supported among cpfg's preprocessor lines"},
  };
  for (const CompileErrorCase& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_EQ(errorOf(c.text), c.message);
  }
  // Expressions nested deeper than the parser allows are an error, not a stack overflow.
  std::string deep = "axiom: A(" + std::string(300, '(') + "1" + std::string(300, ')') + ")\n";
  EXPECT_EQ(errorOf(deep), "test.ls:1:209: nested more than 200 levels deep");
  // An unknown define: override names the grammar's constants.
  try {
    compile("define: a = 1\naxiom: A\n", test::defines({{"nope", 1}}));
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()),
              "test.ls: cannot set \"nope\": the grammar defines no such constant (its define: constants: a)");
  }
}

TEST(GrammarErrors, DiagnosticShowsTheLineAndACaret) {
  const std::string text = "axiom: A\nA -> B(1 +)\n";
  try {
    compile(text);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(renderDiagnostic(text, e), " 2 | A -> B(1 +)\n   |           ^\n");
  }
  // Tabs are kept in the caret line so that it lines up.
  EXPECT_EQ(renderDiagnostic("\tA -> B(\n", 1, 8), " 1 | \tA -> B(\n   | \t      ^\n");
  EXPECT_EQ(renderDiagnostic("one line\n", 3, 1), "");
  EXPECT_EQ(renderDiagnostic("x", Error("f", "/plants/0", "not a line")), "");
}

// --- errors at run time: they name the rule -------------------------------------------

TEST(GrammarErrors, RunTimeErrorsNameTheRule) {
  const CompileErrorCase cases[] = {
      {"axiom: A(0)\nA(x) -> B(1/x)\n",
       "test.ls:2:12: division by zero in production `A(x) -> B(1/x)` (rewriting module 0, A(0), in step 1)"},
      {"axiom: A(3)\nA(x) : x % (x - 3) == 0 -> B\n",
       "test.ls:2:10: modulo by zero in production `A(x) : x % (x - 3) == 0 -> B` (rewriting module 0, A(3), in "
       "step 1)"},
      {"axiom: A(-1)\nA(x) -> B(sqrt(x))\n",
       "test.ls:2:11: sqrt(-1): square root of a negative number in production `A(x) -> B(sqrt(x))` (rewriting "
       "module 0, A(-1), in step 1)"},
      {"axiom: A(1)\nA(x) -> A(x * 1e30 * 1e30)\n",
       "test.ls:2:9: parameter 1 of A is not a finite number (1e+60) in production `A(x) -> A(x * 1e30 * 1e30)` "
       "(rewriting module 0, A(1), in step 1)"},
      {"axiom: X\nX -> A : 1\nX -> B : -2\n",
       "test.ls:3:1: probability -2 is not a finite number >= 0 in production `X -> B : -2` (rewriting module 0, "
       "X, in step 1)"},
      {"axiom: A(0)\ndecomposition:\nA(x) -> B(2/x)\n",
       "test.ls:3:12: division by zero in decomposition rule `A(x) -> B(2/x)` (decomposing A(0) in step 0)"},
      {"axiom: A(0)\ninterpretation:\nA(x) -> F(1/x)\n",
       "test.ls:3:12: division by zero in interpretation rule `A(x) -> F(1/x)` (drawing module 0, A(0), in step "
       "1)"},
      {"global: g = 1\nStart: { g = g / 0; }\naxiom: A\n", "test.ls:2:16: division by zero in the Start block"},
      // Query kinds and parameter counts that are only known when a rule emits the query.
      {"axiom: A(7)\nA(k) -> ?E(k, 1, 0)\n",
       "test.ls:2:9: unknown ?E query kind 7 (SURFACE, HIT, LIGHT, ATTRACT or FACING) in production `A(k) -> ?E(k, "
       "1, 0)` (rewriting module 0, A(7), in step 1)"},
      {"axiom: A(3)\nA(k) -> ?E(k, 0, 0, 0, 0, 0)\n",
       "test.ls:2:9: ?E(LIGHT, ...) takes 1 to 5 parameters, 6 here in production `A(k) -> ?E(k, 0, 0, 0, 0, 0)` "
       "(rewriting module 0, A(3), in step 1)"},
      {"axiom: A(9)\ninterpretation:\nA(k) -> ?E(k, 1)\n",
       "test.ls:3:9: unknown ?E query kind 9 (SURFACE, HIT, LIGHT, ATTRACT or FACING) in interpretation rule `A(k) "
       "-> ?E(k, 1)` (drawing module 0, A(9), in step 0)"},  // found when step 0's queries are answered
      {"axiom: F ~leaf(1, 3)\n",
       "test.ls: interpretation: module 1 ~leaf(1, 3): leaf shape 3 does not exist (the grammar has 1 leaf shape, 0 "
       "to 0)"},
      {"axiom: !(0) F\n",
       "test.ls: interpretation: module 1 F: segments need a width > 0, the turtle's is 0 (set by ! or width:)"},
      {"axiom: @R(0, 0, 0)\n", "test.ls: interpretation: module 0 @R(0, 0, 0): the heading must not be zero"},
  };
  for (const CompileErrorCase& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_EQ(errorOf(c.text, 1), c.message);
  }
}

TEST(GrammarErrors, LimitsGiveAClearErrorInsteadOfRunningOutOfMemory) {
  EXPECT_EQ(errorOf("max length: 1000\nderivation length: 20\naxiom: A\nA -> A A\n"),
            "test.ls: step 10 would make the string longer than 1000 modules (its limit); raise `max length:` in the "
            "grammar, or derive fewer steps");
  // The default limit stops runaway growth long before memory does.
  EXPECT_EQ(errorOf("derivation length: 100\naxiom: A\nA -> A A\n"),
            "test.ls: step 25 would make the string longer than 20000000 modules (its limit); raise `max length:` in "
            "the grammar, or derive fewer steps");
  EXPECT_EQ(errorOf("axiom: A\ndecomposition:\nA -> A B\n"),
            "test.ls:3:1: decomposition goes deeper than its maximum depth 1 (rule `A -> A B` still applies to A); "
            "raise `maximum depth:` in the decomposition: section");
  EXPECT_EQ(errorOf("max length: 500\naxiom: A\ninterpretation:\nmaximum depth: 1000\nA -> F A A\n"),
            "test.ls: interpretation draws more than 500 modules (the length limit); raise `max length:` or "
            "lower the interpretation rules' maximum depth");
  EXPECT_EQ(errorOf("axiom: A\ninterpretation:\nA -> F A\n"),
            "test.ls:3:1: interpretation goes deeper than its maximum depth 1 (rule `A -> F A` still applies to A); "
            "raise `maximum depth:` in the interpretation: section");
}

}  // namespace
}  // namespace tendril::lsystem

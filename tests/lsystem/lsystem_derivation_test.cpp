// Derivations checked against results known from The Algorithmic Beauty of Plants (ABOP).
#include "lsystem/lsystem_test_util.h"
#include "support/determinism.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <tuple>

namespace tendril::lsystem {
namespace {

using test::compile;
using test::countOf;
using test::derived;

TEST(LSystemDerivation, AlgaeLengthsFollowTheFibonacciNumbers) {
  // ABOP §1.2: Lindenmayer's Anabaena, A -> AB, B -> A.
  LSystem ls(loadGrammarFile(test::grammarPath("algae.ls")), test::steps(30));
  EXPECT_EQ(ls.text(), "A");
  const char* first[] = {"AB", "ABA", "ABAAB", "ABAABABA", "ABAABABAABAAB"};
  for (const char* expected : first) {
    ls.step();
    EXPECT_EQ(ls.text(), expected);
  }
  uint64_t a = 8, b = 13;  // lengths after steps 4 and 5: Fibonacci numbers
  EXPECT_EQ(ls.string().size(), 13u);
  while (!ls.finished()) {
    ls.step();
    uint64_t next = a + b;
    a = b;
    b = next;
    ASSERT_EQ(ls.string().size(), b) << "after step " << ls.stepCount();
  }
  EXPECT_EQ(ls.string().size(), 2178309u);  // F(32)
}

// Module counts of ABOP Fig. 1.24's bracketed plants against the counts their productions
// imply (each symbol's count follows a linear recurrence).
struct Counts {
  double f = 0, x = 0, open = 0, turns = 0;
  double total() const { return f + x + 2 * open + turns; }
};

TEST(LSystemDerivation, BracketedPlantsHaveTheModuleCountsTheirProductionsImply) {
  struct Case {
    const char* file;
    int steps;
    // Per F and per X of the predecessor: the F, X, [ and +/- its successor holds.
    Counts perF, perX;
  };
  const Case cases[] = {
      {"abop-1.24a.ls", 5, {5, 0, 2, 2}, {0, 1, 0, 0}},
      {"abop-1.24b.ls", 5, {5, 0, 3, 2}, {0, 1, 0, 0}},
      {"abop-1.24c.ls", 4, {8, 0, 2, 8}, {0, 1, 0, 0}},
      {"abop-1.24d.ls", 7, {2, 0, 0, 0}, {2, 3, 2, 3}},
      {"abop-1.24e.ls", 7, {2, 0, 0, 0}, {2, 3, 2, 2}},
      {"abop-1.24f.ls", 5, {2, 0, 0, 0}, {3, 4, 3, 5}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    LSystem ls(loadGrammarFile(test::grammarPath(c.file)));
    ASSERT_EQ(ls.derivationLength(), c.steps);
    Counts n;
    (ls.text() == "F" ? n.f : n.x) = 1;
    ls.derive();
    for (int i = 0; i < c.steps; ++i) {
      Counts m;
      m.f = n.f * c.perF.f + n.x * c.perX.f;
      m.x = n.f * c.perF.x + n.x * c.perX.x;
      m.open = n.open + n.f * c.perF.open + n.x * c.perX.open;
      m.turns = n.turns + n.f * c.perF.turns + n.x * c.perX.turns;
      n = m;
    }
    EXPECT_EQ(double(countOf(ls, "F")), n.f);
    EXPECT_EQ(double(countOf(ls, "X")), n.x);
    EXPECT_EQ(double(countOf(ls, "[")), n.open);
    EXPECT_EQ(double(countOf(ls, "]")), n.open);
    EXPECT_EQ(double(countOf(ls, "+") + countOf(ls, "-")), n.turns);
    EXPECT_EQ(double(ls.string().size()), n.total());
  }
  // ABOP's own figure: 1.24a after 5 steps has 5^5 segments.
  LSystem a(loadGrammarFile(test::grammarPath("abop-1.24a.ls")));
  a.derive();
  EXPECT_EQ(countOf(a, "F"), 3125u);
}

TEST(LSystemDerivation, ContextSensitiveSignalMovesOneModulePerStep) {
  // ABOP §1.8: ω = baaaaaaaa, b < a -> b, b -> a.
  LSystem ls(compile("axiom: baaaaaaaa\nb < a -> b\nb -> a\n"), test::steps(9));
  std::string expected = "baaaaaaaa";
  for (int i = 0; i < 9; ++i) {
    EXPECT_EQ(ls.text(), expected) << "step " << i;
    ls.step();
    expected.pop_back();  // the signal moves one module to the right
    expected.insert(0, 1, 'a');
  }
  EXPECT_EQ(ls.text(), "aaaaaaaaa");
}

TEST(LSystemDerivation, SignalsFlowIntoEveryBranchOfABracketedString) {
  // The left context skips sibling branches and climbs out of a branch to its parent (ABOP
  // §1.8): an acropetal signal reaches both branches and the main axis in step.
  LSystem ls(compile("ignore: +\naxiom: b a [ + a a ] a [ a ] a\nb < a -> b\nb -> a\n"), test::steps(4));
  const char* steps[] = {"ba[+aa]a[a]a", "ab[+aa]a[a]a", "aa[+ba]b[a]a", "aa[+ab]a[b]b", "aa[+aa]a[a]a"};
  for (const char* s : steps) {
    EXPECT_EQ(ls.text(), s);
    ls.step();
  }
}

TEST(LSystemDerivation, RightContextsEnterBranchesAndSkipTheOnesTheyDoNotName) {
  EXPECT_EQ(derived("axiom: A[X]C\nA > C -> Y\n", 1), "Y[X]C");           // the branch is skipped
  EXPECT_EQ(derived("axiom: A[X][B]C\nA > [B]C -> Y\n", 1), "Y[X][B]C");  // the second branch matches
  EXPECT_EQ(derived("axiom: A[BD]C\nA > [B]C -> Y\n", 1), "Y[BD]C");      // ] skips the rest of a branch
  EXPECT_EQ(derived("axiom: A[X]D\nA > [B]D -> Y\n", 1), "A[X]D");
  EXPECT_EQ(derived("axiom: [A]B\nA > B -> Y\n", 1), "[A]B");  // B is not in A's branch
  // Parameters of context modules are bound; consider: lists what contexts see.
  EXPECT_EQ(derived("consider: A B\naxiom: A(1) + C B(2)\nA(x) < C > B(y) -> D(x + y)\n", 1), "A(1)+D(3)B(2)");
}

TEST(LSystemDerivation, ParametricDerivationMatchesABOPFigure1_30) {
  // ABOP §1.10.1, Fig. 1.30: ω = B(2)A(4,4).
  LSystem ls(compile(R"(
axiom: B(2) A(4, 4)
A(x, y) : y <= 3 -> A(x*2, x+y)
A(x, y) : y > 3 -> B(x) A(x/y, 0)
B(x) : x < 1 -> C
B(x) : x >= 1 -> B(x-1)
)"),
             test::steps(5));
  const char* expected[] = {"B(2)A(4, 4)", "B(1)B(4)A(1, 0)", "B(0)B(3)A(2, 1)", "CB(2)A(4, 3)", "CB(1)A(8, 7)",
                            "CB(0)B(8)A(1.14286, 0)"};
  for (const char* e : expected) {
    EXPECT_EQ(ls.text(), e);
    ls.step();
  }
}

TEST(LSystemDerivation, GlobalsStartEachEndEachAndEnd) {
  LSystem ls(compile(R"(
derivation length: 4
define: k = 2
global: total = 10
Start: { steps = 0; }
StartEach: { steps += 1; }
EndEach: { if (steps == 2) { marker = k * 100; } else marker = marker + 1; }
End: { done = total + steps; }
axiom: A(0)
A(n) -> A(n + steps)
)"));
  ls.derive();
  EXPECT_EQ(ls.text(), "A(10)");  // 1 + 2 + 3 + 4
  EXPECT_EQ(ls.global("steps"), 4.0);
  EXPECT_EQ(ls.global("marker"), 202.0);
  EXPECT_EQ(ls.global("done"), 14.0);
}

TEST(LSystemDerivation, ProductionsAssigningGlobalsRunInStringOrder) {
  LSystem ls(compile("global: n = 0\naxiom: A A A A\nA -> B(n) : 1\n"), test::steps(1));
  // A stochastic group of one member, to be sure groups work with assignments too.
  ls.derive();
  EXPECT_EQ(ls.text(), "B(0)B(0)B(0)B(0)");
  LSystem counter(compile("global: n = 0\naxiom: A A A A\nA : { n = n + 1; } -> B(n)\n"), test::steps(1));
  counter.derive();
  EXPECT_EQ(counter.text(), "B(1)B(2)B(3)B(4)");
}

TEST(LSystemDerivation, ConditionsBlocksAndLocals) {
  EXPECT_EQ(derived(R"(
axiom: A(1) A(5) A(-2)
A(x) : { y = x * 2; } y > 4 { z = y + 1; } -> B(z)
A(x) : x < 0 -> C(abs(x), x > -3 && x < 0, x == -2 ? 7 : 8)
)",
                    1),
            "A(1)B(11)C(2, 1, 7)");
}

TEST(LSystemDerivation, MathFunctionsUseDegrees) {
  EXPECT_EQ(derived("axiom: A\nA -> B(sin(30), cos(60), atan2(1, 1), sqrt(16), 2^3^2, -2^2, 7 % 3, min(4, 2, 9))\n",
                    1),
            "B(0.5, 0.5, 45, 4, 512, -4, 1, 2)");
}

TEST(LSystemDerivation, DecompositionRunsToItsMaximumDepth) {
  const char* g = R"(
axiom: A
A -> A B
decomposition:
maximum depth: 2
B -> C D
C -> E
)";
  EXPECT_EQ(derived(g, 2), "AEDED");
  // The axiom is decomposed too.
  EXPECT_EQ(derived("axiom: B\ndecomposition:\nmaximum depth: 2\nB -> C D\nC -> E\n", 0), "ED");
}

TEST(LSystemDerivation, CutRemovesTheRestOfABranch) {
  EXPECT_EQ(derived("axiom: F[XAB]C\nA -> %\n", 1), "F[X]C");
  EXPECT_EQ(derived("axiom: F[AB[D]E]C\nA -> %\n", 1), "FC");  // % first: the branch goes whole
  EXPECT_EQ(derived("axiom: F A B C\nA -> %\n", 1), "F");       // on the main axis: to the end
  EXPECT_EQ(derived("axiom: F[A[B]]G\nA -> X%\n", 1), "F[X]G");
}

TEST(LSystemDerivation, StochasticChoiceIsReproducibleFromTheSeed) {
  const std::string g = test::grammarPath("abop-1.27-stochastic.ls").string();
  auto run = [&](uint64_t seed) {
    LSystem ls(loadGrammarFile(g), test::seeded(seed));
    ls.derive();
    return ls.text();
  };
  EXPECT_EQ(run(1), run(1));
  EXPECT_EQ(run(7), run(7));
  EXPECT_NE(run(1), run(2));
  // The grammar's own seed: is the default.
  LSystem ls(loadGrammarFile(g));
  ls.derive();
  EXPECT_EQ(ls.text(), run(1));
}

TEST(LSystemDerivation, StochasticFrequenciesMatchTheProbabilities) {
  // 200 000 independent choices: each frequency lies within 5 standard deviations of its
  // probability (a false alarm has probability < 1e-6 per run, and the run is deterministic).
  const int n = 200000;
  std::string axiom;
  for (int i = 0; i < n; ++i) axiom += "X";
  LSystem big(compile("axiom: " + axiom + "\nX -> B : 0.2\nX -> C : 0.5\nX -> D : w * 0.3\ndefine: w = 1\n"),
              test::steps(1, 11));
  big.derive();
  const std::pair<const char*, double> expected[] = {{"B", 0.2}, {"C", 0.5}, {"D", 0.3}};
  for (auto [name, p] : expected) {
    double f = double(countOf(big, name)) / n;
    double sigma = std::sqrt(p * (1 - p) / n);
    EXPECT_NEAR(f, p, 5 * sigma) << name;
  }
  // Weights are relative: 1 : 3 behaves as 0.25 : 0.75.
  LSystem rel(compile("axiom: " + axiom + "\nX -> B : 1\nX -> C : 3\n"), test::steps(1, 3));
  rel.derive();
  double f = double(countOf(rel, "B")) / n;
  EXPECT_NEAR(f, 0.25, 5 * std::sqrt(0.25 * 0.75 / n));
}

TEST(LSystemDerivation, StochasticChoiceIsAmongTheMembersWhoseConditionsAndContextsHold) {
  // One group of four members. X(0) may only become C or D (weights 1 : 4); X(1) B or C (2 : 1);
  // X(2), which sees Y on its right, B, C or P (2 : 1 : 3). A group whose matching members all
  // weigh 0 is passed over. Frequencies lie within 5 standard deviations, as above.
  const int n = 50000;
  std::string axiom;
  for (int i = 0; i < n; ++i) axiom += "X(0) X(1) X(2) Y Z ";
  LSystem ls(compile("axiom: " + axiom + R"(
X(k) : k > 0 -> B(k) : 2
X(k) -> C(k) : 1
X(k) : k == 0 -> D(k) : 4
X(k) > Y -> P(k) : 3
X(k) -> E
Z -> A : 0
Z -> G
)"),
             test::steps(1, 17));
  ls.derive();
  std::map<std::pair<std::string, float>, size_t> made;
  const LString& str = ls.string();
  for (size_t i = 0; i < str.size(); ++i)
    ++made[{ls.grammar().module(str.ids[i]).name, str.paramCount(i) ? str.paramsOf(i)[0] : -1.0f}];
  const std::tuple<const char*, float, double> expected[] = {
      {"C", 0, 0.2}, {"D", 0, 0.8}, {"B", 1, 2.0 / 3}, {"C", 1, 1.0 / 3},
      {"B", 2, 2.0 / 6}, {"C", 2, 1.0 / 6}, {"P", 2, 3.0 / 6}};
  size_t total = 0;
  for (auto [name, k, p] : expected) {
    size_t count = made[{name, k}];
    total += count;
    EXPECT_NEAR(double(count) / n, p, 5 * std::sqrt(p * (1 - p) / n)) << name << "(" << k << ")";
  }
  EXPECT_EQ(total, size_t(3 * n));  // nothing else came of the X modules
  EXPECT_EQ(countOf(ls, "E"), 0u);
  EXPECT_EQ(countOf(ls, "G"), size_t(n));
  EXPECT_EQ(countOf(ls, "A"), 0u);
}

TEST(LSystemDerivation, ResultIsTheSameForAnyThreadCount) {
  // Large enough for many parallel chunks; stochastic, parametric and with random functions.
  const std::string g = R"(
derivation length: 14
angle: 30
axiom: A(1)
A(x) -> F(x) [+ A(x * uniform(0.5, 0.9))] [- A(x * 0.7)] A(x * 0.8) : 0.6
A(x) -> F(x) /(ran(90)) A(x * 0.9) : 0.4
F(l) -> F(l * 1.01)
)";
  const auto one = tendril::test::sameAtEveryThreadCount([&] {
    LSystem ls(compile(g), test::seeded(5));
    ls.derive();
    return std::pair<size_t, uint64_t>{ls.string().size(), plant::contentHash(ls.interpret())};
  });
  EXPECT_GT(one.first, 50000u);
}

}  // namespace
}  // namespace tendril::lsystem

// How a guided integrator splits its budget between learning and rendering (Müller et al. 2017,
// "Practical Path Guiding", sec. 5.2 and its implementation), shared by guided-pt and the guided
// bidirectional integrators (bidir_guiding.h).
//
// Training passes double: pass 0 renders 2 iterations (one sample per pixel each) with the BSDF
// alone, pass k >= 1 renders 2^k, samples with the field learned by the passes before it and
// records into the next one. Rendering starts when
//  - with a sample budget B, after the next pass fewer than twice its length would remain
//    (Müller's rule: the last pass takes the rest, never a sliver of a pass);
//  - with a time budget, the same rule with the next pass's predicted seconds (twice the last);
//  - with either, learning stopped paying: with tau_k = V_k B_k (the variance of pass k's image
//    times the budget it took, samples or seconds) and R_k the budget left at its start, the
//    final image's variance had training stopped after pass k is V^_k = tau_k / R_k. Müller
//    stops at the first rise of V^ (it is convex when training has diminishing returns, sec.
//    5.2); the variances of passes are too noisy for that here, so rendering starts after the
//    first k >= 5 where V^ rose twice in a row (V^_k > V^_{k-1} > V^_{k-2}). On door-ajar
//    (320x240, 60 s) one rise stopped training after 80 iterations in one run of three (the
//    per-sample variance of a 32-sample pass was flat, 26.3 -> 26.0), and the render was 1.21x
//    better than `pt`; the two that trained to 272 iterations reached 17.8-18.7 per sample and
//    1.44-1.47x. Passes of 2-8 samples per pixel once stopped training after 8.
// Rendering passes record nothing: they cost only the sampling. With a sample budget there is
// one, guided, to the end (per sample, the learned selection probability already falls back
// to the BSDF where the guide does not help). With a time budget, guiding must also pay for its
// time, which trials decide: one pass guided and one unguided of equal length, and the one
// with the lower variance x seconds (the inverse of efficiency; the seconds of the median
// iteration, so that a stall of the machine does not decide) wins. A trial is a sequential
// test: where the passes' variances come with their standard errors and the two efficiencies
// differ by less than twice the error of their ratio, it renders another round (one more
// guided and one more unguided pass of the same length) and decides on the pooled rounds, at
// most kMaxTrialRounds of them and only while the time left holds eight more. One round of 8
// iterations each measured each variance within +-10%: door-ajar (320x240, where guiding is
// 1.5x as efficient) lost its early trial at one seed in ten (0.93x) and cornell-glass
// (160x160, guiding 1.17x worse) won it at one in ten (1.08x). The first trial (8 iterations
// each) follows training pass 3: if guiding clearly loses (training would
// cost more time on top), rendering starts unguided at once (an easy scene stops paying for
// training early); if it clearly wins, training goes on and the render stays guided; a tie
// (no clear difference after its rounds) trains on, and a trial after training decides, on
// the better field. Without a decisive early trial (a tie, or training stopped earlier), one
// follows training (half the last training pass each, at least 8). A
// two-sample unguided pass 0 cannot decide this: its variance estimate misses the rare, bright
// paths that dominate scenes such as door-ajar (2 spp measured 32 per sample there, 43 over the
// whole unguided render). Without a budget (an integrator driven iteration by iteration) training
// never stops.
//
// Determinism: with a sample budget the decisions depend on the passes' variances only, which
// the inverse-variance combiner computes in a fixed order; only time budgets read the clock.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace caustica {

class TrainingSchedule {
 public:
  TrainingSchedule() = default;
  // spp > 0: a sample budget; else seconds > 0: a time budget; neither: train forever.
  TrainingSchedule(int spp, double seconds) : spp_(spp), seconds_(seconds) {}

  // Called before each iteration, in order from 0: whether it starts a new pass (never for
  // iteration 0). `elapsed` is the seconds since the render began (time budgets only).
  bool starts_pass(uint32_t iteration, double elapsed);
  // After a pass has ended (starts_pass returned true): its variance (V_k, the variance of its
  // pixel mean; negative: unknown) and that estimate's standard error (negative: unknown, and a
  // trial then decides on its first round). Decides what the pass now starting does.
  void end_pass(double variance, double variance_error = -1);

  int pass() const { return pass_; }
  // Whether the current pass records what it sees (training passes).
  bool learning() const { return phase_ == Phase::Training; }
  // Whether the pass that just ended (when starts_pass returned true) was a training pass: its
  // records are to be learned, as training pass ended_training_pass().
  bool ended_learning() const { return ended_phase_ == Phase::Training; }
  int ended_training_pass() const { return training_pass_; }  // valid until end_pass()
  int training_passes() const { return training_pass_ + 1; }  // started, the current included
  // Whether the current pass samples the learned field.
  bool guided() const;
  bool final_pass() const { return phase_ == Phase::Rendering; }
  bool in_trial() const { return phase_ == Phase::TrialGuided || phase_ == Phase::TrialUnguided; }
  // The first iteration of the rendering passes, the ones after training and its trials (-1
  // while training goes on).
  int64_t rendering_from() const { return rendering_from_; }
  // Why training stopped: "budget" (too little left for another pass), "variance" (V^ rose)
  // or "trial" (guiding lost the early trial); empty while training.
  const char* reason() const { return reason_; }
  // The early trial's verdict: "won" (the render stays guided), "lost" (unguided at once),
  // "tie" (no clear difference: training goes on and a trial after it decides); empty before.
  const char* early_trial() const { return early_verdict_; }

  // For each completed training pass, V^_k as above (negative when unknown, and for pass 0).
  const std::vector<double>& predicted_final_variances() const { return predicted_; }
  // The last trial of a time budget, guided and unguided: the per-sample variance pooled over
  // its rounds times the median iteration's seconds (negative until measured).
  double trial_guided_tau() const { return trial_tau_[1]; }
  double trial_unguided_tau() const { return trial_tau_[0]; }
  // The rounds the last trial took (0 before any), and the standard error of the log of its
  // efficiency ratio (negative: unknown).
  int trial_rounds() const { return trial_rounds_; }
  double trial_log_ratio_error() const { return trial_log_error_; }

 private:
  enum class Phase { Training, TrialGuided, TrialUnguided, Rendering };
  static constexpr size_t kFirstVarianceStop = 5;  // the variance rule from training pass 5 on
  static constexpr uint32_t kMinTrial = 8;         // iterations per trial pass, at least
  static constexpr size_t kEarlyTrialAfter = 3;    // time budgets: the first trial
  static constexpr int kMaxTrialRounds = 4;
  static constexpr double kTrialZ = 2;  // a difference of kTrialZ standard errors decides
  static constexpr double kTrialRoundsInRest = 8;  // another round: the time left holds 8 rounds
  void stop_training(const char* reason);
  void start_trial(uint32_t length);
  // One arm (guided or unguided) of a trial, pooled over its rounds.
  struct TrialArm {
    double samples = 0;             // iterations
    double moment = 0;              // sum over rounds of V_r n_r^2 (n_r: its iterations)
    double error2 = 0;              // sum over rounds of (E_r n_r^2)^2 (E_r: V_r's standard error)
    bool error_known = true;        // every round came with its error
    std::vector<double> seconds;    // of each iteration
    double median_seconds() const;  // 0 without iterations
    // Per-sample variance times the median iteration's seconds: a few slow iterations
    // (another process, a page fault storm) do not decide the trial. Negative: unknown.
    double tau() const;
    double relative_error() const;  // of tau's variance factor; negative: unknown
  };
  void add_round(TrialArm& arm, double variance, double variance_error);
  // After an unguided trial pass: the efficiencies differ by kTrialZ errors of their ratio (or
  // the errors are unknown), and whether no further round is needed.
  bool trial_is_clear() const;
  bool trial_decided() const;
  void train_on();  // the next training pass

  int spp_ = 0;
  double seconds_ = 0;
  Phase phase_ = Phase::Training;
  Phase ended_phase_ = Phase::Training;
  int pass_ = 0;           // passes started, trials included
  int training_pass_ = 0;  // the current or last training pass
  bool early_trial_ = false;
  uint32_t pass_start_ = 0;  // first iteration of the current pass
  uint32_t pass_length_ = 2;
  double pass_start_seconds_ = 0;
  double last_seconds_ = 0;  // when the last iteration ended
  TrialArm trial_[2];        // [guided]
  struct Ended {
    uint32_t start = 0, length = 0;
    double start_seconds = 0, seconds = 0;
  } ended_;  // the pass that ended last
  int64_t rendering_from_ = -1;
  bool rendering_guided_ = true;
  const char* reason_ = "";
  const char* early_verdict_ = "";
  bool early_won_ = false;
  std::vector<double> predicted_;
  double trial_tau_[2] = {-1, -1};  // [guided]
  int trial_rounds_ = 0;
  double trial_log_error_ = -1;
};

}  // namespace caustica

// The variables of Fanuc Custom Macro B (Series 0i-MF operator's manual,
// B-64604EN, "Custom macro", "Types of variables"): #0 is always vacant;
// #1-#33 are local, one set for the main program and one for each G65
// call (its arguments); #100-#199 and #500-#999 are common to all levels.
// Every variable starts vacant (<vacant>, never set), a state apart from
// zero. #500-#999 keep their values between runs on the control: unknown
// offline unless a parameter file gives them. System variables (#1000 on)
// are the control's own (its modal state, offsets, clocks, alarms): not
// read here.
#pragma once

#include <array>
#include <optional>
#include <vector>

namespace volmap::nc::flatten {

/// #1-#33 (index 0 unused): a call level's local variables.
using FanucLocals = std::array<std::optional<double>, 34>;

class FanucVariables {
 public:
  FanucVariables() : locals_(1) {}

  /// A value a parameter file gives (#100-#199, #500-#999).
  void load(int number, double value);
  /// The value, or nullopt for vacant. Throws ValueError (flatten/
  /// parameters.h) for a system variable or a number no control has.
  std::optional<double> get(int number) const;
  /// Sets (nullopt: makes it vacant). Throws ValueError for #0, a system
  /// variable (#3000 raises an alarm: named so) or a number no control has.
  void set(int number, std::optional<double> value);

  /// A G65 call: new locals, the arguments among them.
  void push_call(const FanucLocals& arguments) { locals_.push_back(arguments); }
  void pop_call() { locals_.pop_back(); }

 private:
  std::vector<FanucLocals> locals_;
  std::array<std::optional<double>, 100> common_{};  ///< #100-#199
  std::array<std::optional<double>, 500> kept_{};    ///< #500-#999
};

}  // namespace volmap::nc::flatten

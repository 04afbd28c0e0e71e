// Uses installed volmap as a third-party program would: reads a machine and
// its errors (paths given on the command line) and prints the tool-tip error
// at the machine's home position. Exits 1 unless the error is finite and not
// zero (the sample errors move the tip), so a broken install cannot pass.
#include <cmath>
#include <fstream>
#include <iostream>

#include "core/model/error_model.h"
#include "core/model/errors_csv.h"
#include "core/model/machine_json.h"
#include "postproc/three_axis/post_program.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: consumer MACHINE.json ERRORS.csv\n";
    return 2;
  }
  std::ifstream machine_file(argv[1]), errors_file(argv[2]);
  const volmap::Machine machine = volmap::read_machine_json(machine_file, argv[1]);
  const volmap::ErrorModel model(machine, volmap::read_errors_csv(errors_file, argv[2]));
  const Eigen::Vector3d tip_error_mm = model.exact(machine.home).dP_mm;
  std::cout << "tip error at home, um: " << tip_error_mm.transpose() * 1000.0 << "\n";
  return std::isfinite(tip_error_mm.norm()) && tip_error_mm.norm() > 0 ? 0 : 1;
}

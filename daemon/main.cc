// selfcald: the calibration daemon. Waits for signed requests over LCM, moves the arm through a
// scan plan while recording, calibrates, validates, and installs the new model or says why not.
#include "daemon/service_main.h"

int main(int argc, char** argv) {
  return selfcal::daemon::RunService(argc, argv, selfcal::daemon::MakeDefaultEngine);
}

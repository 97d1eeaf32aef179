#include "runner/interrupt.h"

#include <signal.h>
#include <unistd.h>

#include <cstring>

namespace cellbake {
namespace {

const char* g_message = "";
volatile sig_atomic_t g_relay_interrupted = 0;
volatile pid_t g_relay_child = 0;
struct sigaction g_relay_previous {};

extern "C" void on_interrupt(int) {
  (void)!::write(STDERR_FILENO, "\n", 1);
  (void)!::write(STDERR_FILENO, g_message, std::strlen(g_message));
  (void)!::write(STDERR_FILENO, "\n", 1);
  ::_exit(130);
}

extern "C" void on_relayed_interrupt(int) {
  g_relay_interrupted = 1;
  if (g_relay_child > 0) ::kill(g_relay_child, SIGTERM);
}

}  // namespace

InterruptRelay::InterruptRelay() {
  g_relay_interrupted = 0;
  g_relay_child = 0;
  struct sigaction action {};
  action.sa_handler = on_relayed_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, &g_relay_previous);
}

InterruptRelay::~InterruptRelay() {
  ::sigaction(SIGINT, &g_relay_previous, nullptr);
  g_relay_child = 0;
}

void InterruptRelay::relay_to(pid_t child) {
  g_relay_child = child;
  if (g_relay_interrupted) ::kill(child, SIGTERM);
}

bool InterruptRelay::interrupted() const { return g_relay_interrupted != 0; }

void exit_on_interrupt(const char* message) {
  g_message = message;
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
}

}  // namespace cellbake

// SerialPort on real pseudo-terminals: the error messages of every refusal at open, raw mode, and
// restoring the previous settings on close.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <grp.h>
#include <pty.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "hardware/serial_port.h"
#include "tests/hardware/serial_test_util.h"

namespace graspbed::hardware {
namespace {

// A pty pair kept open for the test's lifetime.
struct Pty {
  Pty() {
    char name[256] = {};
    EXPECT_EQ(openpty(&master, &slave, name, nullptr, nullptr), 0);
    path = name;
  }
  ~Pty() {
    ::close(master);
    ::close(slave);
  }
  int master = -1;
  int slave = -1;
  std::string path;
};

PortError OpenError(const std::string& path, int baud = 115200) {
  SerialPort port;
  try {
    port.Open(path, baud);
  } catch (const PortError& error) {
    return error;
  }
  ADD_FAILURE() << "opening " << path << " did not fail";
  return PortError(PortErrorKind::kOther, "");
}

TEST(SerialPort, MissingPortSaysSo) {
  const PortError error = OpenError("/dev/graspbed-no-such-port");
  EXPECT_EQ(error.kind(), PortErrorKind::kMissing);
  EXPECT_NE(std::string(error.what()).find("/dev/graspbed-no-such-port does not exist"), std::string::npos)
      << error.what();
}

TEST(SerialPort, DanglingEmulatorLinkIsMissing) {
  const std::string link = test_support::UniqueLinkPath("dangling");
  ASSERT_EQ(symlink("/dev/pts/999999", link.c_str()), 0);
  const PortError error = OpenError(link);
  ::unlink(link.c_str());
  EXPECT_EQ(error.kind(), PortErrorKind::kMissing) << error.what();
}

TEST(SerialPort, SecondOpenIsBusy) {
  Pty pty;
  SerialPort first;
  first.Open(pty.path, 2000000);
  const PortError error = OpenError(pty.path);
  EXPECT_EQ(error.kind(), PortErrorKind::kBusy);
  EXPECT_NE(std::string(error.what()).find("busy"), std::string::npos) << error.what();
  first.Close();
  SerialPort again;
  EXPECT_NO_THROW(again.Open(pty.path, 2000000));  // released on close
}

TEST(SerialPort, NotATerminalAndBadBaud) {
  const std::string file = test_support::UniqueLinkPath("file");
  std::ofstream(file) << "x";
  EXPECT_EQ(OpenError(file).kind(), PortErrorKind::kNotATty);
  ::unlink(file.c_str());
  Pty pty;
  const PortError error = OpenError(pty.path, 12345);
  EXPECT_EQ(error.kind(), PortErrorKind::kBadBaud);
  EXPECT_NE(std::string(error.what()).find("baud = 12345"), std::string::npos) << error.what();
}

TEST(SerialPort, PermissionDeniedNamesTheGroupToJoin) {
  if (getuid() != 0) GTEST_SKIP() << "needs root to drop to another user";
  const struct group* dialout = getgrnam("dialout");
  if (dialout == nullptr) GTEST_SKIP() << "no dialout group on this system";
  Pty pty;
  // Make it look like a USB serial device: root:dialout, 0660.
  ASSERT_EQ(chown(pty.path.c_str(), 0, dialout->gr_gid), 0);
  ASSERT_EQ(chmod(pty.path.c_str(), 0660), 0);
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  const pid_t child = fork();
  if (child == 0) {
    // Child: become nobody, try to open, report the message through the pipe.
    ::close(pipe_fds[0]);
    if (setgid(65534) != 0 || setuid(65534) != 0) _exit(3);
    std::string message = "opened";
    try {
      SerialPort port;
      port.Open(pty.path, 115200);
    } catch (const PortError& error) {
      message = std::to_string(static_cast<int>(error.kind())) + "|" + error.what();
    }
    [[maybe_unused]] const ssize_t n = ::write(pipe_fds[1], message.data(), message.size());
    _exit(0);
  }
  ::close(pipe_fds[1]);
  std::string message;
  char buffer[512];
  for (ssize_t n; (n = ::read(pipe_fds[0], buffer, sizeof(buffer))) > 0;) message.append(buffer, n);
  ::close(pipe_fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(message.substr(0, 2), std::to_string(static_cast<int>(PortErrorKind::kPermission)) + "|")
      << message;
  EXPECT_NE(message.find("permission denied"), std::string::npos) << message;
  EXPECT_NE(message.find("group 'dialout'"), std::string::npos) << message;
  EXPECT_NE(message.find("usermod -aG dialout"), std::string::npos) << message;
}

TEST(SerialPort, RawModeBaudAndRestoreOnClose) {
  Pty pty;
  termios before{};
  ASSERT_EQ(tcgetattr(pty.slave, &before), 0);
  ASSERT_TRUE(before.c_lflag & ECHO);  // a fresh pty is cooked
  {
    SerialPort port;
    port.Open(pty.path, 2000000);
    termios during{};
    ASSERT_EQ(tcgetattr(pty.slave, &during), 0);
    EXPECT_FALSE(during.c_lflag & (ECHO | ICANON));
    EXPECT_EQ(cfgetospeed(&during), static_cast<speed_t>(B2000000));
    // Bytes pass unchanged both ways, 0x00 and 0x0A included.
    const uint8_t out[] = {0x00, 0x0A, 0x0D, 0xFF, 0x11};
    EXPECT_EQ(port.Write(out, 100).bytes, sizeof(out));
    uint8_t got[8] = {};
    ASSERT_EQ(::read(pty.master, got, sizeof(got)), static_cast<ssize_t>(sizeof(out)));
    EXPECT_EQ(0, memcmp(got, out, sizeof(out)));
    ASSERT_EQ(::write(pty.master, out, sizeof(out)), static_cast<ssize_t>(sizeof(out)));
    uint8_t in[8] = {};
    const IoResult r = port.Read(in, 1000);
    EXPECT_EQ(r.bytes, sizeof(out));
    EXPECT_EQ(0, memcmp(in, out, sizeof(out)));
    EXPECT_EQ(port.Read(in, 5).status, IoStatus::kTimeout);
  }
  termios after{};
  ASSERT_EQ(tcgetattr(pty.slave, &after), 0);
  EXPECT_EQ(after.c_lflag, before.c_lflag);
  EXPECT_EQ(cfgetospeed(&after), cfgetospeed(&before));
}

TEST(SerialPort, HangupWhenTheOtherSideCloses) {
  auto* pty = new Pty;
  SerialPort port;
  port.Open(pty->path, 115200);
  ::close(pty->master);
  pty->master = ::open("/dev/null", O_RDONLY);  // keep the destructor's close harmless
  uint8_t in[8];
  EXPECT_EQ(port.Read(in, 1000).status, IoStatus::kHangup);
  delete pty;
}

}  // namespace
}  // namespace graspbed::hardware

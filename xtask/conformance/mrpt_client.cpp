// MRPT's CSickLaserSerial (libmrpt-hwdrivers) as an independent LMS200 client for
// `cargo xtask conformance`: initialises against the device on argv[1] (38400 baud, mm mode,
// 180 deg / 0.5 deg, as in trace E of lms200-init-traces.md) and prints argv[2] scans, one line
// each: "SCAN <n> <r0>:<valid0> <r1>:<valid1> ..." with ranges in metres, then "BAUD <bps>":
// the line speed the port was left at (the pty keeps its termios while the emulator holds it).
#include <mrpt/hwdrivers/CSickLaserSerial.h>
#include <mrpt/obs/CObservation2DRangeScan.h>

#include <fcntl.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <thread>

int main(int argc, char** argv)
{
	if (argc < 3)
	{
		std::fprintf(stderr, "usage: %s PORT N_SCANS\n", argv[0]);
		return 64;
	}
	const int wanted = std::atoi(argv[2]);
	try
	{
		mrpt::hwdrivers::CSickLaserSerial laser;
		laser.setSerialPort(argv[1]);
		laser.setBaudRate(38400);
		laser.setMillimeterMode(true);
		laser.setScanFOV(180);
		laser.setScanResolution(50);
		laser.initialize();
		int got = 0;
		int idle = 0;
		while (got < wanted && idle < 3000)
		{
			bool there_is = false, hw_error = false;
			mrpt::obs::CObservation2DRangeScan obs;
			laser.doProcessSimple(there_is, obs, hw_error);
			if (hw_error)
			{
				std::fprintf(stderr, "mrpt_client: hardware error\n");
				return 2;
			}
			if (!there_is)
			{
				++idle;
				std::this_thread::sleep_for(std::chrono::milliseconds(5));
				continue;
			}
			idle = 0;
			++got;
			const size_t n = obs.getScanSize();
			std::printf("SCAN %zu", n);
			for (size_t i = 0; i < n; ++i)
				std::printf(" %.4f:%d", obs.getScanRange(i), obs.getScanRangeValidity(i) ? 1 : 0);
			std::printf("\n");
			std::fflush(stdout);
		}
		if (got < wanted)
		{
			std::fprintf(stderr, "mrpt_client: only %d of %d scans\n", got, wanted);
			return 3;
		}
	}
	catch (const std::exception& e)
	{
		std::fprintf(stderr, "mrpt_client: %s\n", e.what());
		return 1;
	}
	// The speed MRPT set on the port.
	const int fd = open(argv[1], O_RDWR | O_NOCTTY | O_NONBLOCK);
	struct termios t;
	if (fd < 0 || tcgetattr(fd, &t) != 0)
	{
		std::fprintf(stderr, "mrpt_client: cannot read the port's speed\n");
		return 4;
	}
	const speed_t s = cfgetospeed(&t);
	close(fd);
	std::printf("BAUD %d\n", s == B9600 ? 9600 : s == B19200 ? 19200 : s == B38400 ? 38400 : s == B500000 ? 500000 : -1);
	return 0;
}

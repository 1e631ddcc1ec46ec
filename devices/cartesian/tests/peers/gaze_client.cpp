// icub-main's C++ gaze client (ClientGazeController, compiled here from ../shared/peers'
// icub-main sources: the peers' build leaves the gazecontrollerclient plugin off) against
// a gaze controller: stores a context, looks at the points given on the command line
// (x y z each) with lookAtFixationPointSync + waitMotionDone, prints the fixation point
// getFixationPoint reads, then restores the context.
#include <cstdio>
#include <cstdlib>
#include <yarp/os/Network.h>
#include <yarp/os/Property.h>
#include <yarp/os/Time.h>
#include <yarp/sig/Vector.h>

#include "ClientGazeController.h"

int main(int argc, char* argv[]) {
    if (argc < 2 || (argc - 2) % 3 != 0) {
        std::fprintf(stderr, "usage: %s REMOTE [x y z]...\n", argv[0]);
        return 2;
    }
    yarp::os::Network yarp;
    yarp::os::Property opt;
    opt.put("remote", argv[1]);
    opt.put("local", "/cpp_gaze_client");
    ClientGazeController client;
    if (!client.open(opt)) {
        std::printf("OPEN FAILED\n");
        return 1;
    }
    yarp::dev::IGazeControl* gaze = &client;
    int ctx = -1;
    bool stored = gaze->storeContext(&ctx);
    std::printf("STORED %d %d\n", stored ? 1 : 0, ctx);
    gaze->setNeckTrajTime(1.0);
    for (int i = 2; i + 3 <= argc; i += 3) {
        yarp::sig::Vector x(3);
        for (int k = 0; k < 3; k++) x[k] = std::atof(argv[i + k]);
        bool ok = gaze->lookAtFixationPointSync(x);
        bool done = ok && gaze->waitMotionDone(0.02, 10.0);
        yarp::os::Time::delay(0.1);
        yarp::sig::Vector fp;
        bool got = gaze->getFixationPoint(fp);
        std::printf("FIX %d %d %d %s\n", ok ? 1 : 0, done ? 1 : 0, got ? 1 : 0,
                    fp.toString(6).c_str());
    }
    // the reflexes' gains and the stabilisation (refused by a server without IMU)
    double vor = -1.0, ocr = -1.0;
    bool gains = gaze->getVORGain(&vor) && gaze->getOCRGain(&ocr);
    bool stab = gaze->setStabilizationMode(true);
    bool stab_on = true;
    gaze->getStabilizationMode(&stab_on);
    std::printf("REFLEXES %d %.3f %.3f %d %d\n", gains ? 1 : 0, vor, ocr, stab ? 1 : 0,
                stab_on ? 1 : 0);
    bool restored = gaze->restoreContext(ctx);
    double t = 0.0;
    gaze->getNeckTrajTime(&t);
    std::printf("RESTORED %d %.3f\n", restored ? 1 : 0, t);
    client.close();
    std::printf("CLOSED\n");
    return 0;
}

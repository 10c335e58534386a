// bricklayer-simcam: the simulated camera as a process on the bus (SimcamNode).
#include "bricklayer/runtime/node_main.h"
#include "bricklayer/simcam/simcam_node.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::simcam::SimcamNode>(argc, argv); }

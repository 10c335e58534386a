// bricklayer-vision: blocks from camera frames as a process on the bus (VisionNode).
#include "bricklayer/runtime/node_main.h"
#include "bricklayer/vision/vision_node.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::vision::VisionNode>(argc, argv); }

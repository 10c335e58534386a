// bricklayer-status: the operator's status page as a process on the bus (StatusNode).
#include "bricklayer/runtime/node_main.h"
#include "bricklayer/status/status_node.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::status::StatusNode>(argc, argv); }

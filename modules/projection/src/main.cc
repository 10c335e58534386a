// bricklayer-projection: the augmented-reality display behind the board, as a process on the bus
// (ProjectionNode: its configuration, subscriptions and outputs are described in projection_node.h).
#include "bricklayer/projection/projection_node.h"
#include "bricklayer/runtime/node_main.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::projection::ProjectionNode>(argc, argv); }

// bricklayer-prediction: the collapse prediction as a process on the bus (PredictionNode).
#include "bricklayer/prediction/prediction_node.h"
#include "bricklayer/runtime/node_main.h"

int main(int argc, char** argv) { return bricklayer::runtime::node_main<bricklayer::prediction::PredictionNode>(argc, argv); }

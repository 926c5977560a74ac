// Placeholder until the CLI lands (being written in this session).
#include <cstdio>
int main() { std::puts("tvf"); return 0; }

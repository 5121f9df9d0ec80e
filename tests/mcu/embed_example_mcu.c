/* The Cortex-M main of docs/embed_example.c: its lines out through semihosting. */
#include "embed_example.h"
#include "mcu_rt.h"

int main(void)
{
    mcu_puts("docs/embed_example.c on a Cortex-M\n");
    return mvt_embed_example(mcu_puts);
}

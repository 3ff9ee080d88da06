/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "ctl/ctl_pager.h"

static const char *pager_command(void) {
        const char *e = getenv("SYSTEMD_PAGER");
        if (!e)
                e = getenv("PAGER");
        if (!e)
                return "less";
        if (!*e || strcmp(e, "cat") == 0)
                return NULL;
        return e;
}

int ctl_pager_open(ctl_pager *p) {
        int fd[2];

        p->pid = 0;
        if (!isatty(STDOUT_FILENO))
                return 0;
        const char *cmd = pager_command();
        if (!cmd)
                return 0;
        if (pipe(fd) < 0)
                return -errno;

        fflush(stdout);
        pid_t pid = fork();
        if (pid < 0) {
                int r = -errno;
                close(fd[0]);
                close(fd[1]);
                return r;
        }
        if (pid == 0) {
                /* the pager: reads the pipe, writes the terminal */
                if (dup2(fd[0], STDIN_FILENO) < 0)
                        _exit(EXIT_FAILURE);
                close(fd[0]);
                close(fd[1]);
                setenv("LESS", "FRXMK", 0);
                signal(SIGINT, SIG_DFL);
                execl("/bin/sh", "sh", "-c", cmd, (char *) NULL);
                execlp("less", "less", (char *) NULL);
                execlp("more", "more", (char *) NULL);
                _exit(EXIT_FAILURE);
        }
        if (dup2(fd[1], STDOUT_FILENO) < 0) {
                int r = -errno;
                close(fd[0]);
                close(fd[1]);
                return r;
        }
        close(fd[0]);
        close(fd[1]);
        p->pid = pid;
        return 0;
}

void ctl_pager_close(ctl_pager *p) {
        if (p->pid <= 0)
                return;
        fflush(stdout);
        /* EOF for the pager: stdout was the only write end left */
        fclose(stdout);
        while (waitpid(p->pid, NULL, 0) < 0 && errno == EINTR)
                ;
        p->pid = 0;
}

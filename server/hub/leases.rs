//! Several servers on one PostgreSQL (docs/serving-several.md): a launched session is stored
//! unowned as `queued`; every server claims sessions while it has free slots (queued ones,
//! and running ones whose lease ran out because their server died), runs them, and renews the
//! lease of each it holds. A server that cannot renew a lease (another server owns the session
//! now, or the database did not answer in time) ends its copy without writing more.
//!
//! The bound: a lease lasts [`LEASE`] from its last renewal and servers look for claimable
//! sessions every [`CLAIM_EVERY`], so a session of a server killed with SIGKILL is claimed by a
//! server with a free slot at most `LEASE + CLAIM_EVERY` (7 s) after the kill, and then resumes
//! as an interrupted session does (a replay of its stored answers, or a remote run from its
//! latest resume checkpoint, which the database keeps). A server renews every [`RENEW_EVERY`]
//! and gives a session up when its last successful renewal is [`GIVE_UP_AFTER`] old, before its
//! lease can have run out, so that two servers never run one session at once.
//!
//! On SQLite none of this runs: one server owns the database, and a launch starts at once.

use std::sync::Arc;
use std::time::Duration;

use tokio::time::{Instant, MissedTickBehavior};

use super::{Hub, plan_of};
use crate::store::{SessionRow, Status};

/// How long a lease holds after its last renewal.
pub const LEASE: Duration = Duration::from_secs(6);
/// How often a server renews the leases it holds.
pub const RENEW_EVERY: Duration = Duration::from_secs(2);
/// How often a server looks for sessions to claim (and at once after a launch or resume here).
pub const CLAIM_EVERY: Duration = Duration::from_secs(1);
/// A server whose renewals have failed this long ends its copies (the lease is about to end).
pub const GIVE_UP_AFTER: Duration = Duration::from_secs(5);

impl Hub {
    /// Sessions this server runs or is about to (their owners are alive and active).
    fn held(&self) -> Vec<String> {
        self.sessions
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .values()
            .filter(|h| h.status().is_active())
            .map(|h| h.id.to_string())
            .collect()
    }

    /// Claim as many sessions as this server has free slots for, and start them.
    pub(super) async fn claim_once(self: &Arc<Self>) {
        let _one_at_a_time = self.claiming.lock().await;
        if self.slots.is_closed() {
            return;
        }
        let free = self
            .config
            .max_running
            .max(1)
            .saturating_sub(self.held().len());
        let rows = match self
            .store
            .claim_sessions(&self.server_id, free, LEASE)
            .await
        {
            Ok(rows) => rows,
            Err(e) => {
                tracing::warn!("claiming sessions: {e}");
                return;
            }
        };
        for row in rows {
            self.start_claimed(row).await;
        }
    }

    async fn start_claimed(self: &Arc<Self>, row: SessionRow) {
        let id = row.id.clone();
        let taken_over = row.status != Status::Queued;
        if taken_over {
            tracing::warn!(session = %id, "taking over a session whose server's lease ran out");
        } else {
            tracing::info!(session = %id, "claimed a queued session");
        }
        let plan = match plan_of(&row) {
            Ok(plan) => plan,
            Err(e) => {
                tracing::error!(session = %id, "{e}");
                let _ = self
                    .store
                    .set_status(&id, Status::Failed, Some(&e.to_string()))
                    .await;
                return;
            }
        };
        // A remote session resumes from its latest resume checkpoint: the database's copy,
        // written where this server's session thread reads it.
        if plan.spec.env.is_some() {
            match self.store.resume_bytes(&id).await {
                Ok(Some(bytes)) => {
                    if let Err(e) = self.write_checkpoint(&id, "resume", bytes).await {
                        tracing::error!(session = %id, "writing the resume checkpoint: {e}");
                    }
                }
                Ok(None) => {}
                Err(e) => tracing::error!(session = %id, "reading the resume checkpoint: {e}"),
            }
        }
        if let Err(e) = self.start(row, plan).await {
            tracing::warn!(session = %id, "{e}");
        }
    }

    /// Renew the leases of the sessions held here; end the copies whose lease is gone.
    async fn renew(&self, last_ok: &mut Instant) {
        let held = self.held();
        match self.store.renew_leases(&self.server_id, &held, LEASE).await {
            Ok(kept) => {
                *last_ok = Instant::now();
                for id in held.iter().filter(|id| !kept.contains(id)) {
                    tracing::warn!(session = %id, "another server owns this session now");
                    if let Some(h) = self.owned(id) {
                        h.lost();
                    }
                }
            }
            Err(e) => {
                tracing::warn!("renewing leases: {e}");
                if last_ok.elapsed() >= GIVE_UP_AFTER {
                    for id in &held {
                        tracing::warn!(session = %id, "giving up: its lease could not be renewed");
                        if let Some(h) = self.owned(id) {
                            h.lost();
                        }
                    }
                }
            }
        }
    }

    /// Claim and renew until the hub shuts down (PostgreSQL only).
    pub(super) async fn run_leases(self: Arc<Self>) {
        let mut claim = tokio::time::interval(CLAIM_EVERY);
        let mut renew = tokio::time::interval(RENEW_EVERY);
        claim.set_missed_tick_behavior(MissedTickBehavior::Delay);
        renew.set_missed_tick_behavior(MissedTickBehavior::Delay);
        let mut last_ok = Instant::now();
        while !self.slots.is_closed() {
            tokio::select! {
                _ = renew.tick() => self.renew(&mut last_ok).await,
                _ = claim.tick() => {
                    self.claim_once().await;
                    self.check_relays().await;
                }
                () = self.claim_now.notified() => self.claim_once().await,
            }
        }
    }
}
